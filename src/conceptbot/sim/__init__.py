"""PyBullet tabletop simulation: world from a scene, Franka Panda, detector, pick-and-place skill.

This package's own namespace stays free of PyBullet so that the CLI can describe its options
without loading the simulator (PyBullet prints a banner on import).
"""

GRASP_MODES = ("friction", "assisted")
