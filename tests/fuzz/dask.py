"""The fuzz registry's entries for ``spotkin.dask`` (issue 20), the optional Dask wrappers.

``tests/fuzz/registry.py`` calls :func:`register_entries` once its own entries are made; without
Dask installed nothing is registered (and nothing of ``spotkin.dask`` is public there either).

Each function of ``spotkin.dask`` is the *twin* of in-memory entries already in the registry
(``skd.body_ik`` of ``Spot.body_ik`` and ``Robot.body_ik``, ``skd.ik`` of ``Leg.ik``, ``SpotArm.ik`` and
``Chain.ik``, ...): the same argument slots and hostile variants (renamed where the Dask
function names an argument otherwise, plus the model argument), the same documented outputs, and the
twin's oracle on every sample. On top of it, every result must be **bit-identical** to the in-memory
call on the same arguments (the whole batch: the arm's and chains' closed forms may round a sample of
a batch and the same sample alone apart in the last bits, in memory too).

Every plain array argument with at least two rows is passed as a dask array of two chunks along its
first axis (a sample's own numbers split across chunks included), so the graphs are assembled from
several chunks; lists, masked arrays, scalars and other objects go as they are. The result is computed
with the synchronous scheduler (a single sample's status, a 0-d int8 array, is read as the
:class:`spotkin.Status` the in-memory twin returns).
"""

from __future__ import annotations

import copy

import numpy as np

import spotkin as sk

from .entry import REGISTRY, register
from .objects import URDF_CHAINS
from .oracles import finite_check
from .outputs import describe, flatten
from .slots import REJECT, Arg, Custom


def register_entries() -> None:
    try:
        import dask
        import dask.array as da

        import spotkin.dask as skd
    except ImportError:  # the optional extra is not installed
        return

    memory = {entry.name: entry for entry in REGISTRY}

    def chunked(value):
        """A plain array of at least two rows as a dask array of two chunks along its first axis."""
        if type(value) is not np.ndarray or value.ndim == 0 or value.shape[0] < 2 or value.size > 10**7:
            return value
        rows = (value.shape[0] + 1) // 2
        return da.from_array(value, chunks=(rows, *value.shape[1:]), name=False)

    def computed(result, statuses=sk.Status):
        """The lazy result computed, with the in-memory call's structure; a single sample's status
        (a 0-d int8 array) read as a member of ``statuses``, as the in-memory twin returns it."""
        leaves = list(result) if isinstance(result, tuple) else [result]
        if not all(isinstance(leaf, da.Array) for leaf in leaves):
            raise AssertionError(f"not dask arrays: {[type(leaf).__name__ for leaf in leaves]}")
        values = [np.asarray(v) for v in dask.compute(*leaves, scheduler="synchronous")]
        values = [statuses(int(v)) if v.ndim == 0 and v.dtype == np.int8 else v for v in values]
        if not isinstance(result, tuple):
            return values[0]
        return type(result)._make(values) if hasattr(type(result), "_fields") else tuple(values)

    def identical(a, b) -> bool:
        """Same dtype, shape and values (NaN where NaN); a status as its int8 value."""
        a, b = (np.int8(v) if isinstance(v, (sk.Status, sk.StanceStatus)) else v for v in (a, b))
        a, b = np.asarray(a), np.asarray(b)
        return (
            a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
        )

    def model_slot(name, get, other):
        """The model argument: the twin's object, or objects of the wrong kind (TypeError)."""
        return Custom(
            name,
            {
                "valid": lambda c, r, b: Arg(get(c)),
                "none": lambda c, r, b: Arg(None, REJECT, "type"),
                "str": lambda c, r, b: Arg("spot", REJECT, "type"),
                "other": lambda c, r, b: Arg(other(c), REJECT, "type"),
            },
        )

    def renamed(slot, name):
        if slot.name == name:
            return slot
        slot = copy.copy(slot)
        slot.name, slot.aliases = name, (name, *slot.aliases)
        return slot

    def optional(slot):
        """The Dask function's default is None for this argument: None is accepted."""
        slot = copy.copy(slot)
        slot.optional = True
        return slot

    def twin(
        name, covers, function, twin_name, model, rename=None, extra=(), change=None, statuses=sk.Status
    ):
        """An entry for ``function(model, ...)`` after the in-memory entry ``twin_name``; ``rename`` maps
        the Dask function's argument names to the twin's; ``change`` edits the twin's slots."""
        mem = memory[twin_name]
        rename = dict(rename or {})
        back = {old: new for new, old in rename.items()}
        # out= is for in-memory arrays: the Dask functions build their results lazily
        slots = [renamed(slot, back.get(slot.name, slot.name)) for slot in mem.slots if slot.name != "out"]
        if change is not None:
            slots = change(slots)
        slots = [model, *slots, *extra]

        own = {slot.name for slot in mem.slots}

        def to_twin(values: dict) -> dict:
            """The twin's arguments: renamed, without the model and the Dask function's own None
            defaults (a Jacobian's frame, an IK fallback, which the twin may not take)."""
            values = {rename.get(key, key): value for key, value in values.items() if key != model.name}
            return {
                key: value
                for key, value in values.items()
                if key in own and not (value is None and key in ("frame", "point", "fallback"))
            }

        def call(c, **kw):
            """The Dask function's result, computed; it must be bit-identical to the in-memory call on
            the same (whole) arguments, or the case fails with that difference."""
            result = computed(function(**{key: chunked(value) for key, value in kw.items()}), statuses)
            try:
                reference = mem.call(c, **to_twin(kw))
            except Exception as error:
                raise AssertionError(f"the in-memory call raises {type(error).__name__}: {error}") from None
            for k, (a, b) in enumerate(zip(flatten(result), flatten(reference))):
                if not identical(a, b):
                    raise AssertionError(
                        f"leaf {k} is not bit-identical to the in-memory call's: {describe(a)} "
                        f"vs {describe(b)}"
                    )
            return result

        def baseline(c, rng, n):
            samples = mem.baseline(c, rng, n) if mem.baseline else {}
            return {**samples, **{new: samples[old] for new, old in rename.items() if old in samples}}

        def check(x, out, kw, c):
            return (mem.check or finite_check)(to_twin(x), out, to_twin(kw), c)

        nan_rule = mem.nan_rule
        if callable(nan_rule):
            rule = nan_rule

            def nan_rule(x, out, kw, c, spec, rule=rule):
                return rule(to_twin(x), out, to_twin(kw), c, spec)

        pair_rule = None
        if mem.pair_rule is not None:

            def pair_rule(plan, rule=mem.pair_rule):
                return rule(to_twin(plan))

        register(
            name=name,
            covers=covers,
            call=call,
            slots=slots,
            baseline=baseline,
            outputs=mem.outputs,
            check=check,
            nan_rule=nan_rule,
            mixed=mem.mixed,
            expect=mem.expect,
            why=mem.why,
            combos=mem.combos,
            pair_rule=pair_rule,
            overflow_ok=mem.overflow_ok,
            also_raises=mem.also_raises,
            light=name not in full,
        )

    # -- whole body: Spot and two robots from URDFs --
    # (the Dask layer is one code path for every function: full variants for the busiest entries, the
    # light set for the rest)
    full = {"dask.body_ik[spot]", "dask.body_fk[spot]", "dask.ik[leg]", "dask.ik_all[arm]"}
    bodies = {"spot": ("Spot.{}", {}), "hexapod": ("Robot.{}[hexapod]", {})}
    for key, (pattern, rename) in bodies.items():
        robot = model_slot("robot", lambda c, key=key: c.robot(key), lambda c: c.leg)
        for method in ("body_ik", "body_fk", "body_jacobian", "body_rates"):
            name = f"dask.{method}[{key}]"
            twin(name, f"spotkin.dask.{method}", getattr(skd, method), pattern.format(method), robot, rename)

    # -- legs, the Spot Arm, chains --
    models = {
        "leg": (lambda c: c.spot.leg("fl"), "Leg.{}[fl]"),
        "arm": (lambda c: c.arm, "SpotArm.{}"),
        "mdh3": (lambda c: c.chain("mdh3"), "Chain.{}[mdh3]"),
        "dh6": (lambda c: c.chain("dh6"), "Chain.{}[dh6]"),
    }

    def frame_none(name):
        """A Leg's Jacobian has no frame argument: only None is taken."""
        return Custom(
            name,
            {
                "none": lambda c, r, b: Arg(None),
                "base": lambda c, r, b: Arg("base", REJECT, "value"),
                "tool": lambda c, r, b: Arg("tool", REJECT, "value"),
                "index": lambda c, r, b: Arg(1, REJECT, "value"),
            },
            default="omit",
        )

    def none_omits(slot):
        """The Dask function's default is None for this Custom slot: None is accepted (omitted)."""
        slot = copy.copy(slot)
        slot.table = {**slot.table, "none": lambda c, r, b: Arg(None)}
        return slot

    def fallback_nan():
        """Arms and chains answer NaN for a target without a solution: None or "nan" only."""
        return Custom(
            "fallback",
            {
                "none": lambda c, r, b: Arg(None),
                "nan": lambda c, r, b: Arg("nan"),
                "nearest": lambda c, r, b: Arg("nearest", REJECT, "value"),
                "wrong": lambda c, r, b: Arg("nope", REJECT, "value"),
                "int": lambda c, r, b: Arg(1, REJECT),
            },
            default="omit",
        )

    def no_seed():
        """Only the Spot Arm's ik_all takes a seed."""
        return Custom(
            "seed",
            {
                "none": lambda c, r, b: Arg(None),
                "given": lambda c, r, b: Arg(np.zeros(3), REJECT, "type"),
            },
            default="omit",
        )

    def with_optional(name):
        return lambda slots: [optional(slot) if slot.name == name else slot for slot in slots]

    for key, (get, pattern) in models.items():
        model = model_slot("model", get, lambda c: c.spot)
        chain = key in ("mdh3", "dh6", "arm")  # the Spot Arm is a Chain: its Jacobian takes frame and point
        twin(f"dask.fk[{key}]", "spotkin.dask.fk", skd.fk, pattern.format("fk"), model)
        twin(
            f"dask.jacobian[{key}]",
            "spotkin.dask.jacobian",
            skd.jacobian,
            pattern.format("jacobian"),
            model,
            extra=() if chain else (frame_none("frame"), frame_none("point")),
            change=(lambda slots: [none_omits(s) if s.name in ("frame", "point") else s for s in slots])
            if chain
            else None,
        )
        target = {"leg": "p", "arm": "T"}.get(key, "target")
        twin(
            f"dask.ik[{key}]",
            "spotkin.dask.ik",
            skd.ik,
            pattern.format("ik"),
            model,
            {"target": target},
            extra=() if key == "leg" else (fallback_nan(),),
            change=with_optional("fallback")
            if key == "leg"
            # Chain.ik's held joint (7-joint chains) has no Dask form
            else lambda slots: [slot for slot in slots if slot.name not in ("free_joint", "free_value")],
        )
        method = "ik_all"
        twin(
            f"dask.ik_all[{key}]",
            "spotkin.dask.ik_all",
            skd.ik_all,
            pattern.format(method),
            model,
            {"target": target},
            extra=() if key == "arm" else (no_seed(),),
            # Chain.ik's free joint (7-joint chains) has no Dask form
            change=lambda slots: [slot for slot in slots if slot.name not in ("free_joint", "free_value")],
        )

    # -- dynamics: chains from URDFs (their twins are the Chain methods), the robots' standing torques
    # and centres of mass
    for key in URDF_CHAINS:
        for method in (
            "inverse_dynamics",
            "mass_matrix",
            "gravity",
            "nonlinear_effects",
            "coriolis_matrix",
            "forward_dynamics",
            "joint_torques_from_forces",
        ):
            slot = "chain" if method == "joint_torques_from_forces" else "model"
            model = model_slot(slot, lambda c, key=key: c.chain(key), lambda c: c.spot.leg("fl"))
            twin(
                f"dask.{method}[{key}]",
                f"spotkin.dask.{method}",
                getattr(skd, method),
                f"Chain.{method}[{key}]",
                model,
                # the mass matrix's layouts have no Dask form: full matrices only
                change=lambda slots: [slot for slot in slots if slot.name != "layout"],
            )
    for key, cls in (("spot", "Spot"), ("go2", "Robot")):
        robot = model_slot("robot", lambda c, key=key: c.robot(key), lambda c: c.leg)
        twin(
            f"dask.standing_torques[{key}]",
            "spotkin.dask.standing_torques",
            skd.standing_torques,
            f"{cls}.standing_torques[{key}]",
            robot,
            statuses=sk.StanceStatus,
        )
        twin(
            f"dask.floating_q[{key}]",
            "spotkin.dask.floating_q",
            skd.floating_q,
            f"{cls}.floating_q[{key}]",
            robot,
        )
        twin(
            f"dask.center_of_mass[{key}]",
            "spotkin.dask.center_of_mass",
            skd.center_of_mass,
            f"{cls}.center_of_mass[{key}]",
            robot,
        )
