"""Kinematics tools over the models and arrays: differential kinematics (``differential``: damped least
squares, pseudo-inverses, manipulability), Paul's method (``paul``), trajectories (``joint_paths``,
``cartesian_paths``, ``path_planning``) and workspaces by sampling (``workspace``). Above ``model``."""
