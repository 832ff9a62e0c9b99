"""The fuzz harness's machinery: argument slots and their hostile inputs, oracles, the registry of
spotkin's public API, and the pool of worker processes that runs the cases.

Used by ``tests/test_fuzz.py`` (which documents the modes). Overview:

- A **slot** describes one argument: :class:`~fuzz.batch.Batch` (a ``(..., *trailing)`` array with
  batch semantics), :class:`~fuzz.slots.Array` (a fixed-shape array parameter),
  :class:`~fuzz.slots.Real`, :class:`~fuzz.slots.Int`, :class:`~fuzz.slots.Choice` (an enum string),
  :class:`~fuzz.slots.Flag` or :class:`~fuzz.slots.Custom` (an explicit table of values). Each slot
  names its **variants**: hostile inputs (wrong shapes, 0-d and empty arrays, every dtype, byte
  orders, read-only, zero- and negative-stride views, masked arrays, lists, None, NaN, Inf, 1e308,
  subnormals, huge angles, bad enum strings, bad numbers), each with what the documentation promises
  for it: the call must accept it, reject it (``ValueError``/``TypeError``/``MemoryError``), or either.
- An :class:`~fuzz.entry.Entry` of :data:`fuzz.registry.REGISTRY` is one public callable bound to an
  object (for example ``Leg.fk`` on Spot's front-left leg): its slots, a generator of valid baseline
  samples, the outputs it documents (shape and dtype per leaf), and oracles.
- A **case** fuzzes one slot (CI) or two (exhaustive) while the other slots keep a valid
  baseline (a *light* entry, the same code as another entry's on another robot, runs fewer batch
  variants in CI). The worker builds the arguments, calls, and judges the outcome:

  (a) leaves have the documented shape (leading dimensions kept) and dtype (float32 in, float32
      out; every other real dtype float64);
  (b) a sample with NaN/Inf (or an invalid pose) gives NaN floats and INVALID_INPUT in that
      sample only (entry-specific where a sample has parts, such as one leg of four);
  (c) a finite valid sample gives finite results or a documented status/NaN, checked against
      the documentation (fk(ik(p)) = p, references from NumPy and SciPy, Paul residuals...);
  (d) an angle beyond 64 rad gives either NaN/INVALID_INPUT (a documented bound) or the
      result at the angle reduced exactly (``atan2(sin q, cos q)`` with Python's math); a
      time beyond the ends gives the end state;
  (e) every sample of a batch equals a single call on that sample alone.

  Anything else (other exceptions, pybind's "incompatible function arguments", LinAlgError, a
  warning, a crash, a hang) is a failure.

Modules:

- the machinery: :mod:`~fuzz.slots` (outcomes, :class:`~fuzz.slots.Arg`, the parameter slots),
  :mod:`~fuzz.batch` (batch arrays), :mod:`~fuzz.outputs` (result leaves, ``out=``),
  :mod:`~fuzz.entry` (:class:`~fuzz.entry.Entry`, :func:`~fuzz.entry.register`),
  :mod:`~fuzz.objects` (the objects under test, baseline samples), :mod:`~fuzz.urdf_texts`,
  :mod:`~fuzz.oracles`;
- the registry, one module per concept: :mod:`~fuzz.legs`, :mod:`~fuzz.arm`, :mod:`~fuzz.chains`,
  :mod:`~fuzz.body` (whole-body methods), :mod:`~fuzz.spot`, :mod:`~fuzz.robot_options` and
  :mod:`~fuzz.robots` (robots from URDF), :mod:`~fuzz.dynamics`, :mod:`~fuzz.functions`,
  :mod:`~fuzz.paul`, :mod:`~fuzz.trajectory`, :mod:`~fuzz.workspace`, :mod:`~fuzz.gait`,
  :mod:`~fuzz.roundtrip`
  (pickling and copying), :mod:`~fuzz.joint_names`, then :mod:`~fuzz.sdk`, :mod:`~fuzz.dask`,
  :mod:`~fuzz.plot` (optional modules), :mod:`~fuzz.limits`, :mod:`~fuzz.isa` and :mod:`~fuzz.urdf`;
  :mod:`~fuzz.registry` imports them in that order (the order of :data:`~fuzz.registry.REGISTRY`);
- :mod:`~fuzz.canaries` (broken on purpose), :mod:`~fuzz.coverage` (every public callable must
  be registered), :mod:`~fuzz.cases` (the cases of an entry), :mod:`~fuzz.judge` (one case, in a
  worker) and :mod:`~fuzz.worker` (the worker processes and their pool).

The package is imported as ``fuzz``: pytest puts ``tests/`` on ``sys.path`` (no ``__init__.py``
there), and the workers run with ``tests/`` as their working directory and on ``PYTHONPATH``.
"""
