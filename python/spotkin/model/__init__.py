"""The models: legs (``leg``), Spot's arm (``arm``), serial chains (``chain`` with its closed-form IK
in ``chain_ik`` and its dynamics in ``chain_dynamics``; ``mimic`` for chains with mimic joints;
``urdf_chain``: chains from a URDF), the body pose (``body``), whole robots (``robot``) and Spot
(``spot``), and the built-in models as data (``presets``). Above ``_support``, ``dynamics`` and
``urdf``; below everything else."""
