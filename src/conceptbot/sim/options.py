"""Options of a simulator run (:mod:`conceptbot.sim.session`), free of PyBullet so that the CLI and
the web app can hold them without loading the simulator."""

from __future__ import annotations

from dataclasses import dataclass

from conceptbot.sim import GRASP_MODES


@dataclass(frozen=True)
class SimOptions:
    """How a simulator run is set up and recorded.

    Attributes:
        seed: Layout seed (same seed, same world).
        grasp: Grasp mode, one of :data:`~conceptbot.sim.GRASP_MODES`.
        retries: How many more times a step whose grasp slipped or whose placement missed is tried.
        detect: Let the simulated detector set each object's confidence, box and size before
            anything is planned (off: the scene as given).
        gif: Record ``execution.gif`` (costs a small picture after every motion segment).
        gif_size: Width and height of the animation's frames in pixels.
        gif_every: Keep one motion segment in this many (2 halves the animation's size).
    """

    seed: int = 0
    grasp: str = "friction"
    retries: int = 1
    detect: bool = True
    gif: bool = True
    gif_size: tuple[int, int] = (320, 240)
    gif_every: int = 1

    def __post_init__(self) -> None:
        if self.grasp not in GRASP_MODES:
            raise ValueError(f"grasp must be one of {GRASP_MODES}")
        if self.gif_every < 1:
            raise ValueError("gif_every must be 1 or more")
