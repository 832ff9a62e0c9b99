"""The fuzz registry's entries for loading chains from URDF (issue 32): ``Chain.from_urdf`` on the packaged
UR5 and Panda descriptions. ``tests/fuzz/registry.py`` calls :func:`register_entries`.

Hostile sources: None, numbers, lists, garbage bytes, a path's bytes (bytes are XML text), a missing file, a
directory, ``/dev/zero`` (read up to the 64 MiB bound, then refused), empty and non-XML files, loops, planar
and internal floating joints, a legged robot (several chains: no default tip); hostile ``tip`` and ``base``:
unknown links, the root, links above or beside the other, non-str types. The probes check the chain against
the description's own tree walk (``Model.placement``), its joint names and limits, the mimic relation of the
Panda's right finger, and a faithful pickle."""

from __future__ import annotations

import os
import pathlib
import pickle

import numpy as np

import spotkin as sk

from .entry import register
from .outputs import describe
from .slots import ACCEPT, OMIT, REJECT, Arg, Custom


def register_entries() -> None:
    from spotkin import urdf

    def const(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value(c) if callable(value) else value, expect, why)

    def text(name):
        return lambda c: c._get(f"urdf-text:{name}", lambda: sk.robots.text(name))

    def bad(fragment):
        """A UR5 with ``fragment`` added inside <robot>."""
        return lambda c: text("ur5")(c).replace("</robot>", fragment + "</robot>")

    def file(name, expect, why):
        return lambda c, r, b: Arg(c.files()[name], expect, why)

    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # tests/
    source_table = {
        "valid": const(lambda c: sk.robots.path("ur5")),
        "pathlib": const(lambda c: pathlib.Path(sk.robots.path("ur5"))),
        "meshes": const(os.path.join(here, "data", "ur5.urdf")),  # package:// meshes, never read
        "text": const(text("ur5")),
        "text_bytes": const(lambda c: text("ur5")(c).encode()),
        "np_str": const(lambda c: np.str_(text("ur5")(c))),
        "padded_text": const(lambda c: "\n  " + text("ur5")(c)),
        "path_bytes": const(lambda c: os.fsencode(sk.robots.path("ur5")), REJECT, "value"),  # bytes: XML
        "garbage": const(b"\x00\xff\xfe garbage", REJECT, "value"),
        "dev_zero": const("/dev/zero", REJECT, "value") if os.path.exists("/dev/zero") else const(3, REJECT),
        "missing": file("missing", REJECT, "os"),
        "directory": file("directory", REJECT, "os"),
        "empty_path": const("", REJECT, "os"),
        "empty_file": file("empty", REJECT, "value"),
        "not_xml": file("not_xml", REJECT, "value"),
        "loop": file("loop", REJECT, "value"),
        "legged": const(lambda c: sk.robots.path("go2"), REJECT, "value"),
        "planar": const(
            bad(
                '<link name="slider"/><joint name="p" type="planar"><parent link="base_link"/>'
                '<child link="slider"/></joint>'
            ),
            REJECT,
            "value",
        ),
        "floating_inside": const(
            bad(
                '<link name="free"/><joint name="f" type="floating"><parent link="tool0"/>'
                '<child link="free"/></joint>'
            ),
            REJECT,
            "value",
        ),
        "bad_mimic": const(
            lambda c: text("ur5")(c).replace(
                '<joint name="wrist_3_joint" type="revolute">',
                '<joint name="wrist_3_joint" type="revolute"><mimic joint="no_such_joint"/>',
            ),
            REJECT,
            "value",
        ),
        "none": const(None, REJECT, "type"),
        "int": const(3, REJECT, "type"),
        "float": const(1.5, REJECT, "type"),
        "list": const(lambda c: [sk.robots.path("ur5")], REJECT, "type"),
    }
    tip_table = {
        "valid": const("tool0"),
        "ee_link": const("ee_link"),
        "shoulder": const("shoulder_link"),
        "none": const(None),
        "root": const("base_link", REJECT, "value"),  # no joint between the root and itself
        "unknown": const("no_such_link", REJECT, "value"),
        "empty": const("", REJECT, "value"),
        "int": const(3, REJECT, "type"),
        "bytes": const(b"tool0", REJECT, "type"),
        "list": const(["tool0"], REJECT, "type"),
    }
    base_table = {
        "valid": const("base_link"),
        "shoulder": const("shoulder_link"),
        "none": const(None),
        "below": const("tool0", REJECT, "value"),  # nothing moves below the tool frame
        "beside": const("base", REJECT, "value"),  # a link fixed to the root: the tip is not below it
        "unknown": const("no_such_link", REJECT, "value"),
        "int": const(0, REJECT, "type"),
        "path": const(pathlib.Path("base_link"), REJECT, "type"),
    }

    def ur5_pairs(plan):
        if plan.get("tip") == "shoulder" and plan.get("base") == "shoulder":
            return REJECT  # no joint between a link and itself
        return None

    def chain_probe(result, kw, c, expected_tip):
        if not isinstance(result, sk.Chain):
            return f"not a Chain: {describe(result)}"
        source = kw["source"]
        if isinstance(source, (bytes, str)) and (
            isinstance(source, bytes) or source.lstrip().startswith("<")
        ):
            model = urdf.parse_urdf(source.lstrip() if isinstance(source, str) else source)
        else:
            model = urdf.load_urdf(source)
        tip = kw.get("tip", None)
        tip = expected_tip if tip in (None, OMIT) else tip
        base = kw.get("base", None)
        base = model.root if base in (None, OMIT) else base
        path = [j for j in model.path(tip, base) if j.type != "fixed"]
        leaders = []
        for j in path:
            name = j.name if j.mimic is None else j.mimic
            if name not in leaders:
                leaders.append(name)
        if tuple(result.joint_names) != tuple(leaders):
            return f"joint names {result.joint_names}, the path from {base} to {tip} has {leaders}"
        limits = np.array([(model.joint(n).lower, model.joint(n).upper) for n in leaders])
        if not np.array_equal(np.c_[result.lower, result.upper], limits):
            return f"limits {np.c_[result.lower, result.upper].tolist()}, the URDF's are {limits.tolist()}"
        rng = np.random.default_rng(len(leaders))
        q = rng.uniform(-1.0, 1.0, len(leaders))
        if np.isfinite(limits).all():
            q = limits[:, 0] + (limits[:, 1] - limits[:, 0]) * rng.uniform(0, 1, len(leaders))
        values = dict(zip(leaders, q))
        expected = np.linalg.inv(model.placement(base, values)) @ model.placement(tip, values)
        if not np.allclose(result.fk(q), expected, atol=1e-12):
            return f"fk {result.fk(q).tolist()} is not the URDF tree's placement {expected.tolist()}"
        again = pickle.loads(pickle.dumps(result))
        if again.joint_names != result.joint_names or not np.array_equal(again.fk(q), result.fk(q)):
            return "the pickled chain differs"
        return None

    register(
        name="Chain.from_urdf[ur5]",
        covers="spotkin.Chain.from_urdf",
        call=lambda c, **k: sk.Chain.from_urdf(**k),
        slots=[
            Custom("source", source_table),
            Custom("tip", tip_table, default="omit"),
            Custom("base", base_table, default="omit"),
        ],
        pair_rule=ur5_pairs,
        probe=lambda result, kw, c: chain_probe(result, kw, c, "wrist_3_link"),
        also_raises=(OSError,),
    )

    panda_sources = {
        "valid": const(lambda c: sk.robots.path("panda")),
        "meshes": const(os.path.join(here, "data", "panda.urdf")),
        "text": const(text("panda")),
        "none": const(None, REJECT, "type"),
    }
    panda_tips = {
        "valid": const("panda_hand"),
        "right_finger": const("panda_rightfinger"),  # its mimic joint follows the left finger's joint
        "left_finger": const("panda_leftfinger"),
        "link8": const("panda_link8"),
        "ur5_link": const("tool0", REJECT, "value"),
        "int": const(7, REJECT, "type"),
    }
    panda_bases = {
        "valid": const("panda_link0"),
        "link3": const("panda_link3"),
        "hand": const("panda_hand"),  # only the fingers move below the hand
        "finger": const("panda_leftfinger", REJECT, "value"),
    }

    def panda_pairs(plan):
        tip, base = plan.get("tip"), plan.get("base")
        if base == "hand" and tip in ("omit", "valid", "link8"):
            return REJECT  # nothing moves between the hand and itself or above it
        return None

    def panda_probe(result, kw, c):
        problem = chain_probe(result, kw, c, "panda_hand")
        if problem or getattr(result, "full_chain", None) is None:
            return problem
        q = np.linspace(0.0, 0.04, result.dof)
        full = result.full_q(q)
        if not np.array_equal(full, result.mimic_matrix @ q + result.mimic_offset):
            return f"full_q {full} is not M q + b"
        if not np.allclose(result.fk(q), result.full_chain.fk(full), atol=1e-14):
            return "fk is not the full chain's at M q + b"
        return None

    register(
        name="Chain.from_urdf[panda]",
        covers="spotkin.Chain.from_urdf",
        call=lambda c, **k: sk.Chain.from_urdf(**k),
        slots=[
            Custom("source", panda_sources),
            Custom("tip", panda_tips, default="omit"),
            Custom("base", panda_bases, default="omit"),
        ],
        pair_rule=panda_pairs,
        probe=panda_probe,
    )
