"""Reading a ROS ``map_server`` map (a YAML file naming an image) into an occupancy grid.

Semantics followed: Nav2's ``nav2_map_server`` (ROS 2), file
``nav2_map_server/src/map_io.cpp`` of the ``humble`` branch (commit
3c3db59d69, functions ``loadMapYaml`` and ``loadMapFromFile``), which is also
what ROS 1's ``map_server`` does. Read there:

* YAML keys: ``image``, ``resolution``, ``origin`` (three numbers),
  ``negate`` (an integer or a boolean), ``occupied_thresh`` and
  ``free_thresh`` are required; ``mode`` is optional (default ``trinary``,
  matched case-insensitively). A relative ``image`` is relative to the YAML
  file's folder; an ``image`` starting with ``/`` is absolute. A YAML path
  starting with ``~/`` has the home folder put in.
* Each pixel's shade, 0 (black) to 1 (white), is the average of its red,
  green and blue channels over 255; in ``trinary`` mode the alpha channel
  (255 opaque), when the image has one, is averaged in as a fourth channel.
  ``occ = shade`` if ``negate`` else ``1 - shade``.
* ``trinary``: 100 if ``occupied_thresh < occ``, else 0 if ``occ <
  free_thresh``, else -1 (both inequalities strict: a shade exactly at a
  threshold is unknown).
* ``scale``: -1 where the pixel is not opaque (alpha != 255), else 100 if
  ``occupied_thresh < occ``, 0 if ``occ < free_thresh``, else
  ``rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100)``
  (rounding half to even, as C's ``rint``).
* ``raw``: ``round(shade * 255)`` (the channels' average, rounded half away
  from zero) where it is in 0..100, else -1; alpha is ignored.
* The image's top row is the grid's last row: grid row ``r`` is image row
  ``H - 1 - r``. Cell (0, 0)'s lower-left corner is at ``origin[:2]`` and the
  grid is turned by ``origin[2]`` (yaw, radians) about that corner.

Nav2's Rolling and Jazzy branches replaced that loop (pull request #5071,
"Update map_io library to use Eigen method") by ImageMagick's grey
conversion (a weighted luminance, not the average), ``>=``/``<=``
thresholds and alpha < 255 as unknown in trinary mode too; on map_saver's
pure black, white and grey (205) maps both give the same grid.

Stricter than Nav2, each refused with the file and the field named: keys
other than the seven above; a resolution that is not a finite number > 0;
thresholds outside [0, 1] or ``free_thresh >= occupied_thresh`` (what
Nav2's map saver refuses); ``negate`` other than 0, 1, true or false; an
image that is not PGM (P2/P5), PNG or BMP, has 16-bit or floating-point
pixels, or has more than :data:`MAX_MAP_CELLS` pixels (checked from the
header, before the pixels are decoded); a YAML file over
:data:`MAX_MAP_YAML_BYTES`, with aliases, repeated keys or nesting.
Numbers are read as map_server reads them (yaml-cpp converting the text
with a C++ stream): a decimal with an exponent (``resolution: 5e-2``,
``origin: [0, 0, 1e300]``) is a number, as it is in a scenario, although
YAML 1.1 (PyYAML) would read it as text; a value beyond the floats
(``1e400``) is refused as not finite, as map_server refuses it. Quoted
numbers (``resolution: "0.05"``) are refused: a number must be written as
one. A value may be finite and still put the map beyond the floats (a
resolution of ``1e307`` m, an origin of ``1e308`` m): the map's size and
corners must be finite too. Any finite yaw turns the map (``1e300`` rad by
``cos(1e300)``, ``sin(1e300)``).

The values are computed as map_server does, in float64 from the channels'
sum (a table over the possible sums, so a 25-million-pixel image costs its
pixels and one ``int8`` grid, never a float image).
"""

from __future__ import annotations

import dataclasses as dc
import math
import os
import re
import stat
import warnings
from pathlib import Path

import numpy as np

from drake_social.errors import ScenarioError
from drake_social.io.textfile import SHOWN_PATH_CHARACTERS, describe_mode, read_text_file, shorten, yaml_problem

__all__ = ["FREE", "MAP_KEYS", "MAP_MODES", "MAX_MAP_CELLS", "MAX_MAP_IMAGE_BYTES", "MAX_MAP_YAML_BYTES", "OCCUPIED",
           "UNKNOWN", "OccupancyMap", "check_map_field", "classify", "map_values", "read_map"]

#: Cell classes of :attr:`OccupancyMap.classes`.
OCCUPIED, FREE, UNKNOWN = 1, 0, -1
#: The ``mode`` values map_server knows; ``trinary`` is the default.
MAP_MODES = ("trinary", "scale", "raw")
#: The keys of a map YAML, the required ones first (``mode`` is optional).
MAP_KEYS = ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode")
_REQUIRED = MAP_KEYS[:-1]
#: Most pixels (cells) of a map image: 25 million, about 25 MB per ``int8``
#: grid (``values`` and ``classes``), an office floor of 150 x 150 m at
#: 0.03 m or a campus of 250 x 250 m at 0.05 m. A larger image is refused
#: from its header, before its pixels are decoded.
MAX_MAP_CELLS = 25_000_000
#: Largest map image file, bytes: 128 MiB (a 25-million-pixel RGBA BMP is
#: 100 MB; an ASCII PGM of as many pixels up to 100 MB).
MAX_MAP_IMAGE_BYTES = 128 * 1024 * 1024
#: Largest map YAML file, bytes: 64 KiB (map_saver writes about 150 bytes).
MAX_MAP_YAML_BYTES = 64 * 1024
#: Deepest YAML nesting accepted: the document's mapping and ``origin``'s list.
_MAX_DEPTH = 2
#: A decimal number with an exponent, as a C++ stream reads a double
#: (yaml-cpp's ``as<double>``): the forms YAML 1.1 leaves as text (it needs
#: a point and a signed exponent) that map_server reads as numbers.
_EXPONENT_NUMBER = re.compile(r"^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$")
_FORMATS = "a PGM, PNG or BMP image"


def _allowed_keys() -> str:
    return f"{', '.join(_REQUIRED)} (required) and mode (optional, one of {', '.join(MAP_MODES)})"


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_map_field(key: str, value):
    """Checks one field of a map YAML and returns its value as read_map keeps it.

    The one check of a field, shared by :func:`read_map` (which puts the file
    before the message) and :func:`~drake_social.maps.generate.write_map`.
    ``free_thresh`` is checked alone here (in [0, 1]); that it is below
    ``occupied_thresh`` is checked by the callers.

    Args:
        key: one of :data:`MAP_KEYS`.
        value: the value as YAML (PyYAML) gives it.

    Returns:
        ``image``: the text; ``resolution``, the thresholds: float;
        ``origin``: a tuple of three floats; ``negate``: bool; ``mode``: its
        lower-case name.

    Raises:
        ValueError: ``"<what is allowed>, got <value>"`` (without the key).
    """
    got = shorten(repr(value))
    if key == "image":
        if not isinstance(value, str) or not value:
            raise ValueError(f"must be the image's file name (text, relative to the YAML file's folder), got {got}")
        return value
    if key == "resolution":
        if not _is_number(value) or not math.isfinite(value) or not value > 0:
            raise ValueError(f"must be a finite number > 0 metres per cell, got {got}")
        return float(value)
    if key == "origin":
        if (not isinstance(value, (list, tuple)) or len(value) != 3
                or not all(_is_number(v) and math.isfinite(v) for v in value)):
            raise ValueError(f"must be 3 finite numbers [x, y, yaw] (metres, metres, radians), got {got}")
        return tuple(float(v) for v in value)
    if key == "negate":
        if value in (0, 1) and isinstance(value, (bool, int)):
            return bool(value)
        raise ValueError(f"must be 0, 1, true or false, got {got}")
    if key in ("occupied_thresh", "free_thresh"):
        if not _is_number(value) or not 0.0 <= value <= 1.0:
            raise ValueError(f"must be in [0, 1], got {got}")
        return float(value)
    if key == "mode":
        if not isinstance(value, str) or value.lower() not in MAP_MODES:
            raise ValueError(f"{got} is not one of {', '.join(MAP_MODES)}")
        return value.lower()
    raise ValueError(f"unknown key {shorten(repr(key))}; allowed: {_allowed_keys()}")


def classify(values: np.ndarray) -> np.ndarray:
    """The cell classes of map_server values: :data:`OCCUPIED` where 100,
    :data:`FREE` where 0, :data:`UNKNOWN` elsewhere (-1, and ``scale`` or
    ``raw`` values 1..99).

    Args:
        values: map_server's OccupancyGrid values, any shape.

    Returns:
        ``int8`` classes of the same shape.
    """
    values = np.asarray(values)
    out = np.full(values.shape, UNKNOWN, np.int8)
    out[values == 100] = OCCUPIED
    out[values == 0] = FREE
    return out


def map_values(sums: np.ndarray, channels: int, alpha: np.ndarray | None, *, mode: str, negate: bool,
               occupied_thresh: float, free_thresh: float) -> np.ndarray:
    """map_server's values of pixels given by the sum of their channels (see the module docstring).

    Args:
        sums: integer array, any shape: each pixel's sum of ``channels``
            8-bit channels (red, green, blue, and in ``trinary`` mode alpha;
            one channel for a grey image without alpha).
        channels: how many channels were summed (1 to 4).
        alpha: the pixels' alpha (255 opaque), or None (no alpha channel);
            ``scale`` mode makes pixels that are not opaque -1.
        mode: one of :data:`MAP_MODES`.
        negate: whether white is occupied.
        occupied_thresh: occupied above this ``occ``.
        free_thresh: free below this ``occ``.

    Returns:
        ``int8`` values (-1, 0..100) of ``sums``' shape, in the pixels' order.
    """
    # The average of the channels takes at most 255 * 4 + 1 distinct sums:
    # map_server's arithmetic is done once per sum and looked up.
    mean = np.arange(255 * channels + 1, dtype=np.float64) / channels
    if mode == "raw":
        percent = np.floor(mean + 0.5)  # std::round: half away from zero (mean >= 0)
        table = np.where(percent <= 100, percent, -1)
    else:
        shade = mean / 255.0
        occ = shade if negate else 1.0 - shade
        if mode == "trinary":
            middle = np.full_like(occ, -1)
        else:
            middle = np.rint((occ - free_thresh) / (occupied_thresh - free_thresh) * 100.0)
        table = np.where(occupied_thresh < occ, 100, np.where(occ < free_thresh, 0, middle))
    out = table.astype(np.int8)[sums]
    if mode == "scale" and alpha is not None:
        out[alpha != 255] = -1
    return out


@dc.dataclass(frozen=True, eq=False)
class OccupancyMap:
    """A map_server map read: its parameters and its grid.

    The map frame: cell ``(row, col)`` covers ``[col, col + 1) * resolution``
    along x and ``[row, row + 1) * resolution`` along y; the world pose of the
    map frame is ``origin`` (x, y in metres, yaw in radians).

    Attributes:
        path: the YAML file (absolute).
        image_path: the image (absolute).
        resolution: metres per cell (> 0, finite).
        origin: x, y (metres) and yaw (radians) of cell (0, 0)'s lower-left corner.
        negate: whether white is occupied (map_server's ``negate``).
        occupied_thresh: map_server's ``occupied_thresh``.
        free_thresh: map_server's ``free_thresh``.
        mode: ``"trinary"``, ``"scale"`` or ``"raw"``.
        values: (H, W) read-only ``int8``: map_server's OccupancyGrid values
            (-1, 0..100); grid row 0 is the image's bottom row.
        classes: (H, W) read-only ``int8``: :data:`OCCUPIED` where the value
            is 100, :data:`FREE` where 0, :data:`UNKNOWN` elsewhere.
    """

    path: Path
    image_path: Path
    resolution: float
    origin: tuple[float, float, float]
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str
    values: np.ndarray
    classes: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W): rows and columns of the grid."""
        return self.values.shape

    @property
    def width_m(self) -> float:
        """The map's extent along its x axis (columns), metres."""
        return self.values.shape[1] * self.resolution

    @property
    def height_m(self) -> float:
        """The map's extent along its y axis (rows), metres."""
        return self.values.shape[0] * self.resolution

    def rotation(self) -> np.ndarray:
        """R_WM: the (2, 2) rotation from the map frame to the world (by the yaw)."""
        c, s = math.cos(self.origin[2]), math.sin(self.origin[2])
        return np.array([[c, -s], [s, c]])

    def to_world(self, p_M: np.ndarray) -> np.ndarray:
        """World xy of points given in the map frame (metres from cell (0, 0)'s lower-left corner).

        Args:
            p_M: (..., 2) points in the map frame, metres.

        Returns:
            (..., 2) world points, metres.
        """
        return np.asarray(p_M, float) @ self.rotation().T + np.array(self.origin[:2])

    def to_map(self, p_W: np.ndarray) -> np.ndarray:
        """Map-frame xy of world points (the inverse of :meth:`to_world`).

        Args:
            p_W: (..., 2) world points, metres.

        Returns:
            (..., 2) points in the map frame, metres.
        """
        return (np.asarray(p_W, float) - np.array(self.origin[:2])) @ self.rotation()

    def corners(self) -> np.ndarray:
        """(4, 2) world corners of the map's rectangle, counter-clockwise from cell (0, 0)'s lower-left corner."""
        w, h = self.width_m, self.height_m
        return self.to_world(np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]))

    def extent(self) -> np.ndarray:
        """[x_min, y_min, x_max, y_max]: the world axis-aligned bounding box of the (turned) map rectangle, metres."""
        c = self.corners()
        return np.concatenate([c.min(axis=0), c.max(axis=0)])

    def cell_centers(self, rows, cols) -> np.ndarray:
        """World xy of grid cells' centres.

        Args:
            rows: grid rows (0 at the map's bottom), any shape broadcasting with ``cols``.
            cols: grid columns.

        Returns:
            (..., 2) world points, metres.
        """
        rows, cols = np.broadcast_arrays(np.asarray(rows, float), np.asarray(cols, float))
        return self.to_world(np.stack([cols + 0.5, rows + 0.5], axis=-1) * self.resolution)

    def cell_at(self, xy) -> tuple[np.ndarray, np.ndarray]:
        """The grid cell holding each world point.

        A cell holds its lower and left edges (``[col, col + 1)`` cells along
        x), so a point on the map's top or right edge is outside.

        Args:
            xy: (..., 2) world points, metres.

        Returns:
            (rows, cols): ``int64`` arrays of shape ``(...)``, both -1 where
            the point is outside the map (or not finite).
        """
        p_M = self.to_map(xy) / self.resolution
        with np.errstate(invalid="ignore"):
            cols, rows = np.floor(p_M[..., 0]), np.floor(p_M[..., 1])
        h, w = self.shape
        inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)  # False for NaN
        rows = np.where(inside, rows, -1).astype(np.int64)
        cols = np.where(inside, cols, -1).astype(np.int64)
        return rows, cols

    def class_at(self, xy) -> np.ndarray:
        """The class (:data:`OCCUPIED`, :data:`FREE`, :data:`UNKNOWN`) at world points; UNKNOWN outside the map.

        Args:
            xy: (..., 2) world points, metres.

        Returns:
            ``int8`` classes of shape ``(...)``.
        """
        rows, cols = self.cell_at(xy)
        inside = rows >= 0
        return np.where(inside, self.classes[np.where(inside, rows, 0), np.where(inside, cols, 0)],
                        UNKNOWN).astype(np.int8)

    def image_pixel(self, rows, cols) -> tuple[np.ndarray, np.ndarray]:
        """The image pixel of grid cells: ``(H - 1 - row, col)``.

        Args:
            rows: grid rows.
            cols: grid columns.

        Returns:
            (image_rows, image_cols), image row 0 being the image's top row.
        """
        return self.shape[0] - 1 - np.asarray(rows), np.asarray(cols)


def _fail(source: str, message: str) -> ScenarioError:
    return ScenarioError(f"{source}: {message}")


def read_map(path: str | Path, *, source: str | None = None) -> OccupancyMap:
    """Reads a map_server map: the YAML file and the image it names (see the module docstring).

    Args:
        path: the map's YAML file.
        source: how errors name the file (e.g. the scenario and its field);
            default: ``path``.

    Returns:
        The map, its grid read-only.

    Raises:
        ScenarioError: ``"<source>: <field>: <what is wrong and what is
            allowed>"``: the YAML file is missing, too large, not valid YAML,
            has an unknown, repeated or missing key or a value out of range,
            or the image is missing, not a PGM, PNG or BMP image Pillow reads,
            or too large.
    """
    path_text = str(path)
    if path_text.startswith("~/"):  # as Nav2 expands the YAML's name (not the image's)
        path = Path(path_text).expanduser()
    source = source or shorten(path_text, SHOWN_PATH_CHARACTERS)
    try:
        text = read_text_file(path, "map YAML", limit=MAX_MAP_YAML_BYTES)
    except ScenarioError as e:
        if source == shorten(path_text, SHOWN_PATH_CHARACTERS):
            raise
        raise _fail(source, str(e)) from None
    fields = _yaml_fields(text, source)
    values = {}
    for key in MAP_KEYS:
        if key in fields:
            try:
                values[key] = check_map_field(key, fields[key])
            except ValueError as e:
                raise _fail(source, f"{key}: {e}") from None
    if values["free_thresh"] >= values["occupied_thresh"]:
        raise _fail(source, f"free_thresh: must be below occupied_thresh ({values['occupied_thresh']:g}), got "
                            f"{values['free_thresh']:g}")
    mode = values.get("mode", "trinary")
    yaml_path = Path(os.path.abspath(path))
    image_path = Path(os.path.abspath(yaml_path.parent / values["image"]))
    grid = _read_image(image_path, values["image"], source, mode=mode, negate=values["negate"],
                       occupied_thresh=values["occupied_thresh"], free_thresh=values["free_thresh"])
    classes = classify(grid)
    grid.flags.writeable = False
    classes.flags.writeable = False
    out = OccupancyMap(path=yaml_path, image_path=image_path, resolution=values["resolution"],
                       origin=values["origin"], negate=values["negate"], occupied_thresh=values["occupied_thresh"],
                       free_thresh=values["free_thresh"], mode=mode, values=grid, classes=classes)
    _check_extent(out, source)
    return out


def _check_extent(grid: OccupancyMap, source: str) -> None:
    """Refuses a map whose size or corners are beyond the floats, though each value is finite."""
    h, w = grid.shape
    with np.errstate(over="ignore", invalid="ignore"):
        size = (grid.width_m, grid.height_m)
        corners = grid.corners()
    if not all(math.isfinite(v) for v in size):
        raise _fail(source, f"resolution: {grid.resolution!r} m per cell makes the map's {w} x {h} cells "
                            f"{size[0]:g} x {size[1]:g} m; the map's size must be finite")
    if not np.isfinite(corners).all():
        raise _fail(source, f"origin: {list(grid.origin)!r} puts the map's corners beyond the floats; they must be "
                            "finite")


def _yaml_fields(text: str, source: str) -> dict:
    """The top-level mapping of a map YAML, keys checked: no alias, no repeated,
    unknown or missing key, nothing nested deeper than ``origin``'s list."""
    import yaml  # PyYAML

    class Loader(yaml.SafeLoader):
        depth = 0

        def compose_node(self, parent, index):
            event = self.peek_event()
            if isinstance(event, yaml.AliasEvent):
                raise _fail(source, f"line {event.start_mark.line + 1}, column {event.start_mark.column + 1}: an "
                                    "alias; a map YAML gives each value once")
            if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                self.depth += 1
                if self.depth > _MAX_DEPTH:
                    raise _fail(source, f"line {event.start_mark.line + 1}: nested too deeply; a map YAML is one "
                                        f"mapping of {_allowed_keys()}")
            node = super().compose_node(parent, index)
            if isinstance(node, (yaml.MappingNode, yaml.SequenceNode)):
                self.depth -= 1
            return node

    # A plain scalar in exponent form is a float (a quoted one stays text).
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_NUMBER, list("-+0123456789."))
    loader = None
    try:
        loader = Loader(text)  # its reader refuses control characters and NULs at once
        root = loader.get_single_node()
        if root is None:
            raise _fail(source, f"empty; a map YAML is a mapping of {_allowed_keys()}")
        if not isinstance(root, yaml.MappingNode):
            raise _fail(source, f"line {root.start_mark.line + 1}: a map YAML is a mapping of {_allowed_keys()}")
        if root.value and not any(isinstance(k, yaml.ScalarNode) and k.value in MAP_KEYS for k, _ in root.value):
            # Not a map YAML (any file may be named as one): its keys are not repeated.
            raise _fail(source, f"line {root.value[0][0].start_mark.line + 1}: not a map YAML: none of its "
                                f"{len(root.value)} keys is one of {_allowed_keys()}")
        first_line = {}
        for key_node, _ in root.value:
            line = key_node.start_mark.line + 1
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            if key not in MAP_KEYS:
                shown = shorten(repr(key)) if key is not None else "a mapping or list as a key"
                raise _fail(source, f"line {line}: unknown key {shown}; allowed: {_allowed_keys()}")
            if key in first_line:
                raise _fail(source, f"line {line}: {key}: given twice (first at line {first_line[key]}); each key "
                                    "once")
            first_line[key] = line
        missing = [k for k in _REQUIRED if k not in first_line]
        if missing:
            raise _fail(source, f"no {', '.join(missing)}; a map YAML needs {_allowed_keys()}")
        return loader.construct_document(root)
    except yaml.YAMLError as e:
        raise _fail(source, f"not valid YAML: {yaml_problem(e, text)}") from None
    finally:
        if loader is not None:
            loader.dispose()


def _read_image(image_path: Path, named: str, source: str, **parameters) -> np.ndarray:
    """map_server's values of the image (grid row 0 = the image's bottom row), checked as the module docstring says."""
    from PIL import Image  # Pillow

    shown = shorten(str(image_path), SHOWN_PATH_CHARACTERS)
    try:
        st = os.stat(image_path)
    except (FileNotFoundError, NotADirectoryError):
        raise _fail(source, f"image: file {shorten(repr(named))} not found (resolved to {shown})") from None
    except (OSError, ValueError) as e:
        raise _fail(source, f"image: {shown} cannot be read ({getattr(e, 'strerror', None) or e})") from None
    if not stat.S_ISREG(st.st_mode):
        raise _fail(source, f"image: {shown} is {describe_mode(st.st_mode)}, not an image file")
    if st.st_size > MAX_MAP_IMAGE_BYTES:
        raise _fail(source, f"image: {shown} has {st.st_size:,} bytes; a map image may have at most "
                            f"MAX_MAP_IMAGE_BYTES ({MAX_MAP_IMAGE_BYTES:,}) bytes")
    not_image = f"image: {shown} is not {_FORMATS} Pillow can read"
    kind = "image"
    try:
        with open(image_path, "rb") as f:
            head = f.read(8)
            magic = head[:2]
            kind = ("PNG" if head.startswith(b"\x89PNG") else "BMP" if magic == b"BM"
                    else "PGM/PPM" if magic[:1] == b"P" else "image")
            f.seek(0)
            with warnings.catch_warnings():
                # Pillow warns from 89 million pixels and refuses from 179
                # million; MAX_MAP_CELLS, below both, is checked here.
                warnings.simplefilter("ignore", Image.DecompressionBombWarning)
                try:
                    image = Image.open(f, formats=("PPM", "PNG", "BMP"))
                except Image.UnidentifiedImageError:  # its bytes are not repeated: it may be any file
                    raise _fail(source, f"{not_image}: its content is none of them") from None
                except Image.DecompressionBombError as e:
                    count = re.search(r"\((\d+) pixels\)", str(e))
                    pixels = f"{int(count.group(1)):,} pixels" if count else "more pixels than Pillow opens"
                    raise _fail(source, f"image: {shown} has {pixels} (from its header); a map may have at most "
                                        f"MAX_MAP_CELLS ({MAX_MAP_CELLS:,}) cells") from None
            with image:
                if image.format == "PPM" and magic not in (b"P2", b"P5"):  # magic: one of Pillow's PPM kinds
                    raise _fail(source, f"{not_image}: a PPM/PBM file (magic {magic.decode('latin-1')}), not a PGM "
                                        "(P2 or P5)")
                w, h = image.size
                if w * h > MAX_MAP_CELLS:
                    raise _fail(source, f"image: {shown} is {w} x {h} pixels = {w * h:,} cells; a map may have at "
                                        f"most MAX_MAP_CELLS ({MAX_MAP_CELLS:,}) cells")
                if w * h == 0:
                    raise _fail(source, f"image: {shown} is {w} x {h} pixels; a map needs at least one cell")
                sums, channels, alpha = _channel_sums(image, shown, source, parameters["mode"])
    except ScenarioError:
        raise
    except (OSError, ValueError, SyntaxError, EOFError, IndexError, TypeError) as e:
        # Pillow's ways of saying a file is not an image it reads, or is truncated or corrupt. Its
        # message is not repeated: some quote the file's bytes (an ASCII PGM's tokens).
        damage = "truncated" if isinstance(e, EOFError) or "truncated" in str(e) else "corrupt or unsupported"
        raise _fail(source, f"{not_image}: its {kind} data is {damage} ({type(e).__name__})") from None
    values = map_values(sums, channels, alpha, **parameters)
    return np.ascontiguousarray(values[::-1])  # the image's top row is the grid's last row


#: Pillow modes read, and the mode each is converted to first ("" = kept).
_MODES = {"L": "", "LA": "", "RGB": "", "RGBA": "", "1": "L", "La": "LA", "RGBa": "RGBA", "RGBX": "RGB", "PA": "RGBA"}


def _channel_sums(image, shown: str, source: str, mode: str):
    """(sums, channels, alpha) of a Pillow image for :func:`map_values`: the
    per-pixel sum of red, green, blue (and alpha in trinary mode), decoded."""
    if image.mode == "P":  # a palette: its colours, and alpha where it has a transparent entry
        image = image.convert("RGBA" if "transparency" in image.info else "RGB")
    elif image.mode in ("L", "RGB") and "transparency" in image.info:
        # A PNG's tRNS chunk (one grey level or colour transparent): an alpha channel, as map_server reads it.
        image = image.convert("LA" if image.mode == "L" else "RGBA")
    elif image.mode in _MODES:
        if _MODES[image.mode]:
            image = image.convert(_MODES[image.mode])
    else:
        raise _fail(source, f"image: {shown} has pixels of Pillow mode {image.mode!r} (16-bit, floating-point or "
                            f"another colour model); map_server maps are 8-bit grey or colour: modes "
                            f"{', '.join(sorted(_MODES) + ['P'])}")
    pixels = np.asarray(image)
    if image.mode == "L":
        return pixels, 1, None
    colour, alpha = (pixels[..., :-1], pixels[..., -1]) if image.mode in ("LA", "RGBA") else (pixels, None)
    # A grey pixel stands for three equal channels: summed once, averaged over one.
    if colour.ndim == 3 and colour.shape[-1] == 3:
        sums, channels = colour.sum(axis=-1, dtype=np.uint16), 3
    else:
        sums, channels = colour.reshape(colour.shape[:2]).astype(np.uint16), 1
    if mode == "trinary" and alpha is not None:
        if channels == 1:  # grey + alpha: the average of (g, g, g, a)
            sums, channels = sums * 3, 3
        sums, channels = sums + alpha, channels + 1
    return sums, channels, alpha
