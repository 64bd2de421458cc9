"""The shipped Stable-Baselines3 models: read-only package data (``paragym.models``).

``<env name>/<algo>_seed<N>.zip`` with its training config and curve (``.json``, ``.png``).
Found by name from any directory (:func:`paragym.baselines.policies.shipped_models_dir`);
``paragym train`` never writes here (user training goes to ``runs/models``).
"""
