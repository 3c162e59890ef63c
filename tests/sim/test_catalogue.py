"""The object catalogue: coverage of the paper's objects, look-up order, receptacle caps, bad data."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.sim.catalogue import MAX_CONTAINER_HEIGHT_M, MAX_ZONE_FOOTPRINT_M, Catalogue

PAPER_OBJECTS = Path(__file__).parents[2] / "benchmarks" / "data" / "paper_objects.txt"


def test_every_object_in_the_papers_tables_is_catalogued() -> None:
    catalogue = Catalogue.load()
    names = [
        line.strip()
        for line in PAPER_OBJECTS.read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    assert len(names) > 100
    for name in names:
        assert catalogue.spec(name).source == "catalogue", name
    assert catalogue.warnings == []


def test_lookup_falls_back_to_the_head_noun_then_scene_size_then_default() -> None:
    catalogue = Catalogue.load()
    assert catalogue.spec("Stainless Steel Spoon").size_m == catalogue.spec("stainless steel spoon").size_m
    assert catalogue.spec("silver spoon").size_m == catalogue.spec("spoon").size_m
    sized = catalogue.spec("flux capacitor", scene_size=(0.05, 0.04, 0.03))
    assert sized.source == "scene" and sized.size_m == (0.05, 0.04, 0.03)
    guessed = catalogue.spec("thingamajig")
    assert guessed.source == "default" and guessed.shape == "box"
    assert len(catalogue.warnings) == 2 and "thingamajig" in catalogue.warnings[1]


def test_receptacles_are_capped_and_grips_follow_the_shape() -> None:
    catalogue = Catalogue.load()
    trash = catalogue.spec("trash can")
    assert trash.size_m[2] == MAX_CONTAINER_HEIGHT_M and trash.grip == "rim"
    user = catalogue.spec("user")
    assert user.shape == "zone" and max(user.size_m[:2]) <= MAX_ZONE_FOOTPRINT_M and user.mass_kg == 0
    assert catalogue.spec("journal").grip == "edge"
    assert catalogue.spec("teapot").grip == "knob"
    assert catalogue.spec("apple").grip == "body"


@pytest.mark.parametrize(
    "data",
    [
        {"kinds": {}, "objects": {}},
        {"kinds": {"default": {"shape": "blob", "size": [1, 1, 1], "mass": 1, "rgba": [0, 0, 0, 1]}}},
        {
            "kinds": {"default": {"shape": "box", "size": [0.1, 0.1, 0.1], "mass": 1, "rgba": [0, 0, 0, 1]}},
            "objects": {"x": {"kind": "nope"}},
        },
        {
            "kinds": {"default": {"shape": "box", "size": [0.1, 0.1, 0.1], "mass": 1, "rgba": [0, 0, 0, 1]}},
            "objects": {"x": {"size": [0.1, -1, 0.1]}},
        },
    ],
)
def test_a_bad_catalogue_is_a_clear_error(tmp_path: Path, data: dict) -> None:
    path = tmp_path / "objects.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ConfigError):
        Catalogue.load(path)


def test_a_missing_or_malformed_catalogue_file_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no object catalogue"):
        Catalogue.load(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ConfigError):
        Catalogue.load(bad)


def test_a_potted_plant_is_a_solid_pot_under_soft_foliage() -> None:
    sunflower = Catalogue.load().spec("sunflower")
    # 40 cm tall in the catalogue: a 10 cm pot the gripper holds, 30 cm of leaves drawn above it.
    assert sunflower.size_m[2] == pytest.approx(0.1) and sunflower.foliage_m == pytest.approx(0.3)
    assert sunflower.grip == "body" and Catalogue.load().spec("apple").foliage_m == 0.0
