"""Rooms from ROS ``map_server`` maps: a YAML file and an occupancy image read as
map_server reads them (:mod:`~drake_social.maps.read`), their obstacle cells
as a few exact boxes (:mod:`~drake_social.maps.boxes`), and seeded office
floors written as such maps (:mod:`~drake_social.maps.generate`).

Pure numpy, PyYAML and Pillow: no pydrake, no scenario (import layer 1).
"""

from drake_social.maps.boxes import MAP_UNKNOWN_CHOICES, MapBoxes, cells_to_rectangles, map_boxes, row_rectangles
from drake_social.maps.generate import (MAP_IMAGE_FORMATS, OfficeFloorLayout, office_floor_image, office_floor_layout,
                                        ragged_edges, write_map)
from drake_social.maps.read import (FREE, MAP_KEYS, MAP_MODES, MAX_MAP_CELLS, MAX_MAP_IMAGE_BYTES, MAX_MAP_YAML_BYTES,
                                    OCCUPIED, UNKNOWN, OccupancyMap, check_map_field, classify, map_values, read_map)

__all__ = ["FREE", "MAP_IMAGE_FORMATS", "MAP_KEYS", "MAP_MODES", "MAP_UNKNOWN_CHOICES", "MAX_MAP_CELLS",
           "MAX_MAP_IMAGE_BYTES", "MAX_MAP_YAML_BYTES", "OCCUPIED", "UNKNOWN", "MapBoxes", "OccupancyMap",
           "OfficeFloorLayout", "cells_to_rectangles", "check_map_field", "classify", "map_boxes", "map_values",
           "office_floor_image", "office_floor_layout", "ragged_edges", "read_map", "row_rectangles", "write_map"]
