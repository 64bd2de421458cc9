"""The PyBullet layer: a client with bodies by name, mechanism builders, obstacles,
and paper 000's occupancy-grid collision test."""
