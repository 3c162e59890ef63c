"""PyBullet tabletop simulation: world from a scene, Franka Panda, detector, pick-and-place skill.

This package's own namespace stays free of PyBullet so that the CLI can describe its options
and the web app can name the pictures without loading the simulator (PyBullet prints a banner on
import).
"""

GRASP_MODES = ("friction", "assisted")

BEFORE_PNG = "before.png"
AFTER_PNG = "after.png"
EXECUTION_GIF = "execution.gif"
PICTURES = (BEFORE_PNG, AFTER_PNG, EXECUTION_GIF)
"""The files a simulator run writes (:mod:`conceptbot.sim.session`), in the order they are made."""
