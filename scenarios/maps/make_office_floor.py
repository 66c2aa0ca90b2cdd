"""Writes office_floor.pgm and office_floor.yaml here: a seeded 20 x 14 m office
floor at 0.05 m per cell (400 x 280 pixels), as map_server's map_saver writes a
trinary map. Run it again to get the same files bit for bit
(tests/maps/test_generate.py checks that).

    python scenarios/maps/make_office_floor.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_social.maps import office_floor_image, write_map

#: The floor's size (metres), resolution (metres per cell) and seed.
WIDTH_M, HEIGHT_M, RESOLUTION, SEED = 20.0, 14.0, 0.05, 22


def make(directory: Path = Path(__file__).resolve().parent) -> Path:
    """Writes the map into ``directory``; returns its YAML file."""
    image = office_floor_image(WIDTH_M, HEIGHT_M, RESOLUTION, np.random.default_rng(SEED))
    return write_map(directory, "office_floor", image, RESOLUTION)


if __name__ == "__main__":
    print(make())
