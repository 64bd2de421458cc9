"""The papers' kinematics: numpy array functions and the numba kernels they loop over N poses; no
PyBullet, no Gymnasium. One module per mechanism, and :mod:`.geometry` for what they share
(quaternions, part shapes)."""
