"""Loading a scenario: its YAML read, checked against the schema, overridden and validated.

The YAML is read first with PyYAML within nesting and size limits
(:func:`compose_yaml`, the one YAML parser of scenarios, sweeps and
overrides) and checked against the dataclasses of
:mod:`drake_social.scenario.schema` field by field (:func:`check_yaml`:
duplicate keys, unknown keys, types), so that every error names its source,
line and dotted field before Drake's loader builds the dataclasses. Overrides
(``--set``, a sweep's variants) are further YAML documents merged in turn.
The values are then checked by :func:`drake_social.scenario.validate.validate_scenario`.

pydrake and PyYAML are imported where a document is loaded, so that the
pure-numpy core may import the scenario package without Drake.
"""

import dataclasses as dc
import functools
import os
import typing
from pathlib import Path
from typing import Sequence, Union

from drake_social.errors import ScenarioError
from drake_social.io.textfile import read_yaml_file, shorten, yaml_problem
from drake_social.scenario.map_rules import map_extent
from drake_social.scenario.schema import Scenario
from drake_social.scenario.validate import validate_scenario

__all__ = [
    "MAX_YAML_DEPTH",
    "MAX_YAML_NODES",
    "check_node",
    "check_yaml",
    "compose_yaml",
    "load_scenario",
    "load_scenario_text",
]


def load_scenario(path: str | Path, overrides: str | Sequence[str] | None = None, *,
                  overrides_name: str = "overrides") -> Scenario:
    """Loads and validates a scenario file.

    The YAML is read first with PyYAML and checked against the schema field by
    field (:func:`check_yaml`: duplicate keys, unknown keys, types), so that
    every error names its source, line and dotted field (``world.bounds[2]``,
    ``robot.wheels``) before Drake's loader builds the dataclasses.

    Args:
        path: a YAML file following the :class:`Scenario` schema.
        overrides: optional YAML text, or several applied in turn (a later
            one merges into what the earlier ones left), on top of the file, e.g.
            ``"random_seed: 3\\nsocial: {weights: [1, 0, 0, 0, 0]}"``.
        overrides_name: how errors name an override, e.g. ``"--set"``: an
            error caused by one reads ``<path> (--set '<text>'): ...``.

    Returns:
        The validated scenario.

    Raises:
        ScenarioError: the file is missing, not a regular file, larger than
            :data:`~drake_social.io.textfile.MAX_YAML_FILE_BYTES` (4 MiB), malformed, has
            duplicate or unknown keys or invalid values; the message names
            the file (or the override at fault), the line and the field.
    """
    text = read_yaml_file(path, "scenario")  # refuses "" before Path("") could make it the working directory
    return load_scenario_text(text, str(Path(path)), overrides,
                              overrides_name=overrides_name, base_dir=Path(path).parent)


def load_scenario_text(text: str, source: str, overrides: str | Sequence[str] | None = None, *,
                       overrides_name: str = "overrides", base_dir: str | Path | None = None) -> Scenario:
    """Loads and validates a scenario from its YAML text, as :func:`load_scenario` does a file.

    A relative ``people_file`` is resolved against ``base_dir`` and kept as
    that absolute path, so the scenario reads the same file wherever it is used.

    Args:
        text: the scenario's YAML.
        source: how errors name it (the file it came from).
        overrides, overrides_name: as :func:`load_scenario`.
        base_dir: the folder relative file names are resolved against (the
            scenario file's); None = the working directory.

    Raises:
        ScenarioError: as :func:`load_scenario`, naming ``source``.
    """
    from pydrake.common.yaml import yaml_load_typed  # here, not at the top: keeps pydrake out of the core

    sources = [(source, text)]
    for extra in [overrides] if isinstance(overrides, str) else list(overrides or []):
        sources.append((f"{source} ({overrides_name} {shorten(repr(extra))})", extra))
    stages = []
    scenario = None
    bounds_given = False
    for k, (where, data) in enumerate(sources):
        bounds_given |= _sets(check_yaml(data, where, file=k == 0), "world", "bounds")
        try:
            scenario = yaml_load_typed(schema=Scenario, data=data, **({} if scenario is None else
                                                                        {"defaults": scenario}))
        except Exception as e:  # what check_yaml lets through; Drake's message has no file name: add it
            raise ScenarioError(f"{where}: {e}") from e
        _resolve_people_file(scenario, base_dir)
        _resolve_map(scenario, base_dir, bounds_given, where)
        stages.append(scenario)
    # Blame the source after which the scenario stopped being valid: a bad
    # --set is named, not the file it was applied to.
    culprit = len(stages) - 1
    try:
        validate_scenario(stages[culprit], source=sources[culprit][0])
    except ScenarioError:
        while culprit > 0 and not _is_valid(stages[culprit - 1]):
            culprit -= 1
        validate_scenario(stages[-1], source=sources[culprit][0])
    return scenario


def _resolve_people_file(scenario: Scenario, base_dir: str | Path | None) -> None:
    """Makes a relative ``people_file`` absolute, relative to ``base_dir`` (None: the working directory)."""
    name = scenario.people_file
    if name is None or not name.strip() or Path(name).is_absolute():
        return  # an empty name is refused by the validation
    scenario.people_file = str((Path.cwd() if base_dir is None else Path(base_dir)).absolute() / name)


def _sets(root, *keys: str) -> bool:
    """Whether the YAML mapping node ``root`` has the nested key ``keys``."""
    node = root
    for key in keys:
        if getattr(node, "tag", None) != _MAP_TAG:
            return False
        node = next((v for k, v in node.value if getattr(k, "value", None) == key), None)
        if node is None:
            return False
    return True


def _resolve_map(scenario: Scenario, base_dir: str | Path | None, bounds_given: bool, where: str) -> None:
    """Makes a relative ``world.map`` absolute, relative to ``base_dir`` (None:
    the working directory; ``..`` taken lexically), and sets ``world.bounds`` to the map's extent
    when no source has given them."""
    name = scenario.world.map
    if name is None or not name.strip():
        return  # an empty name is refused by the validation
    if not Path(name).is_absolute():
        scenario.world.map = os.path.normpath((Path.cwd() if base_dir is None else Path(base_dir)).absolute() / name)
    if not bounds_given:
        try:
            scenario.world.bounds = map_extent(scenario.world)
        except ScenarioError as e:
            raise ScenarioError(f"{where}: world.map: {e}") from None


def _is_valid(scenario: Scenario) -> bool:
    try:
        validate_scenario(scenario)
    except ScenarioError:
        return False
    return True


# --------------------------------------------------------------------------
# Schema check of the YAML text, before Drake's loader: each error names the
# source, the line and the dotted field, and says what is allowed.


def _describe(tp) -> str:
    """What a value of schema type ``tp`` looks like, for error messages."""
    origin = typing.get_origin(tp)
    if origin is Union:
        alts = [a for a in typing.get_args(tp) if a is not type(None)]
        text = " or ".join(_describe(a) if not dc.is_dataclass(a) else f"!{a.__name__} {{...}}" for a in alts)
        return text + (" or null" if len(alts) < len(typing.get_args(tp)) else "")
    if origin is list:
        return "a list of " + _plural(typing.get_args(tp)[0])
    if origin is dict:
        return "a mapping of names to " + _plural(typing.get_args(tp)[1])
    if dc.is_dataclass(tp):
        return f"a mapping ({tp.__name__}: {', '.join(f.name for f in dc.fields(tp))})"
    return {float: "a number", int: "an integer", bool: "true or false", str: "a string"}.get(tp, str(tp))


def _plural(tp) -> str:
    if typing.get_origin(tp) is Union:
        alts = [a for a in typing.get_args(tp) if a is not type(None)]
        return " or ".join(_plural(a) for a in alts) + (" or nulls" if len(alts) < len(typing.get_args(tp)) else "")
    if typing.get_origin(tp) is list:
        return "lists of " + _plural(typing.get_args(tp)[0])
    if dc.is_dataclass(tp):
        return f"mappings ({tp.__name__}: {', '.join(f.name for f in dc.fields(tp))})"
    return {float: "numbers", int: "integers", bool: "booleans", str: "strings"}.get(tp, str(tp))


#: Deepest nesting of YAML nodes accepted in a scenario, sweep or override,
#: counted as the loader counts it (the document's mapping is level 1, a
#: scalar one more than its collection): the shipped scenarios and
#: studies/example_sweep.yaml need 6, a sweep variant that sets an obstacle's
#: centre 8. Deeper documents are refused before Python's recursion limit is
#: reached.
MAX_YAML_DEPTH = 32
#: Most nodes (mappings, lists, keys and values) of one YAML document, an
#: alias counted as the nodes it stands for: a "billion laughs" of nested
#: aliases is refused while it is read. A 2,000-obstacle room has about 25,000;
#: PyYAML composes about 15,000 nodes a second.
MAX_YAML_NODES = 100_000


class _YamlLimit(Exception):
    def __init__(self, mark, message: str):
        super().__init__(message)
        self.mark = mark


@functools.lru_cache(maxsize=1)
def _limited_loader(yaml):
    """PyYAML's SafeLoader with :data:`MAX_YAML_DEPTH` and :data:`MAX_YAML_NODES` enforced while composing."""

    class Loader(yaml.SafeLoader):
        def __init__(self, stream):
            super().__init__(stream)
            self._depth = 0  # collections open around the node being composed
            self._total = 0  # nodes so far, aliases expanded
            self._size: dict[int, int] = {}  # id(node) -> its expanded node count
            self._height: dict[int, int] = {}  # id(node) -> its expanded nesting depth

        def _count(self, nodes: int, height: int, mark) -> None:
            self._total += nodes
            if self._total > MAX_YAML_NODES:
                raise _YamlLimit(mark, f"more than {MAX_YAML_NODES:,} YAML nodes (aliases counted as the nodes "
                                       f"they repeat); a document may have at most {MAX_YAML_NODES:,}")
            if self._depth + height > MAX_YAML_DEPTH:
                raise _YamlLimit(mark, f"nested more than {MAX_YAML_DEPTH} levels deep (aliases included); "
                                       f"at most {MAX_YAML_DEPTH} are allowed")

        def compose_node(self, parent, index):
            mark = self.peek_event().start_mark
            if self.check_event(yaml.AliasEvent):
                node = super().compose_node(parent, index)
                if id(node) not in self._size:  # its anchor is still open: the alias repeats itself
                    raise _YamlLimit(mark, "an alias inside the node it refers to (a recursive YAML structure)")
                self._count(self._size[id(node)], self._height[id(node)], mark)
                # A node of its own at the alias's place, so that errors name the alias's line (the
                # content, shared, keeps its own lines).
                style = node.style if isinstance(node, yaml.ScalarNode) else node.flow_style
                here = type(node)(node.tag, node.value, mark, mark, style)
                self._size[id(here)], self._height[id(here)] = self._size[id(node)], self._height[id(node)]
                return here
            self._depth += 1
            self._count(0, 0, mark)
            before = self._total
            node = super().compose_node(parent, index)
            self._depth -= 1
            children = (node.value if isinstance(node, yaml.SequenceNode) else
                        [n for pair in node.value for n in pair] if isinstance(node, yaml.MappingNode) else [])
            self._height[id(node)] = 1 + max((self._height[id(c)] for c in children), default=0)
            self._count(1, 0, mark)
            self._size[id(node)] = self._total - before
            return node

    return Loader


def compose_yaml(text: str, source: str):
    """Parses YAML ``text`` into PyYAML's node tree, within the limits.

    The one YAML parser of scenario files, sweep files and overrides
    (``--set``, sweep variants): the document may nest at most
    :data:`MAX_YAML_DEPTH` levels and have at most :data:`MAX_YAML_NODES`
    nodes, aliases counted as the nodes they repeat.

    Args:
        text: the YAML document.
        source: how errors name it (a file, or a file and an override).

    Returns:
        The root node, or None for an empty document.

    Raises:
        ScenarioError: ``<source>: not valid YAML: ...`` or ``<source>: line <n>: <the limit exceeded>``.
    """
    import yaml  # PyYAML, as Drake's Python loader uses; imported here like pydrake

    loader = None
    try:
        loader = _limited_loader(yaml)(text)  # its reader refuses control characters and NULs at once
        return loader.get_single_node()
    except yaml.YAMLError as e:
        raise ScenarioError(f"{source}: not valid YAML: {yaml_problem(e, text)}") from None
    except _YamlLimit as e:
        raise ScenarioError(f"{source}: line {e.mark.line + 1}: {e}") from None
    finally:
        if loader is not None:
            loader.dispose()


def check_yaml(text: str, source: str, schema: type = Scenario, *, file: bool = True):
    """Checks YAML ``text`` against the dataclass ``schema`` before it is loaded.

    Parses it with :func:`compose_yaml` (its nesting and size limits), then
    refuses duplicate keys (PyYAML and Drake keep the last one silently),
    keys the schema does not have and values of the wrong type (a word for a
    number, null or a mapping for a list, an unknown ``!Tag``). Values are
    not range-checked here (see :func:`validate_scenario`).

    A file's text (``file``) must first show that it is a document of its
    kind: a mapping whose top-level keys include a field of ``schema`` (or
    none at all). Until then an error describes what the file holds without
    quoting it, since a scenario or sweep may name any file the process can
    read (:mod:`drake_social.io.textfile`).

    Args:
        text: the YAML document.
        source: how errors name it.
        schema: the dataclass it follows.
        file: whether ``text`` is a file's (False: an override, ``--set``,
            whose text the user typed: its unknown keys are quoted at once).

    Returns:
        The document's root node (:func:`compose_yaml`).

    Raises:
        ScenarioError: ``<source>: line <n>: <dotted field>: <what is allowed>, got <value>``.
    """
    root = compose_yaml(text, source)
    if root is None:
        raise ScenarioError(f"{source}: empty; a {schema.__name__.lower()} is a mapping "
                            f"({', '.join(f.name for f in dc.fields(schema))})")
    if file:
        _check_kind(schema, root, source)
    check_node(schema, root, source)
    return root


def _check_kind(schema: type, root, source: str) -> None:
    """Refuses a file that is not a document of ``schema``'s kind (see
    :func:`check_yaml`), describing what it holds without quoting it."""
    import yaml

    kind = schema.__name__.lower()
    fields = [f.name for f in dc.fields(schema)]
    line = root.start_mark.line + 1
    if not isinstance(root, yaml.MappingNode) or root.tag != _MAP_TAG:
        raise ScenarioError(f"{source}: line {line}: not a {kind} file: a {kind} is a mapping ({', '.join(fields)}), "
                            f"got {_kind_of(root, yaml)}")
    keys = [k for k, _ in root.value]
    if keys and not any(isinstance(k, yaml.ScalarNode) and k.tag == _STR_TAG and k.value in fields for k in keys):
        raise ScenarioError(f"{source}: line {keys[0].start_mark.line + 1}: not a {kind} file: none of its "
                            f"{len(keys)} top-level keys is a field of a {kind} ({', '.join(fields)})")


#: What a YAML node of a standard tag is, for messages that do not quote it.
_KINDS = {"str": "text", "int": "a number", "float": "a number", "bool": "true or false", "null": "null",
          "timestamp": "a date", "seq": "a list", "map": "a mapping"}


def _kind_of(node, yaml) -> str:
    """What ``node`` is (``a list``, ``text``, ``a number`` ...), without its value or its tag's name."""
    if node.tag.startswith(_YAML_TAG) and node.tag[len(_YAML_TAG):] in _KINDS:
        return _KINDS[node.tag[len(_YAML_TAG):]]
    shape = ("a mapping" if isinstance(node, yaml.MappingNode) else "a list" if isinstance(node, yaml.SequenceNode)
             else "a value")
    return f"{shape} with a tag"


def check_node(schema: type, node, source: str, field: str = "") -> None:
    """Checks one composed YAML node (of :func:`compose_yaml`) against ``schema``, as :func:`check_yaml`.

    Args:
        schema: a dataclass, or ``list[...]``, ``dict[str, ...]``, ``Optional[...]`` of the schema types.
        node: the node.
        source: how errors name the document.
        field: the dotted field of ``node`` in its document ("" at the top).
    """
    import yaml

    _check_node(schema, node, field, source, yaml)


#: PyYAML's tags of untagged mappings, lists and strings, and the prefix of its standard (``!!``) tags.
_MAP_TAG = "tag:yaml.org,2002:map"
_SEQ_TAG = "tag:yaml.org,2002:seq"
_STR_TAG = "tag:yaml.org,2002:str"
_YAML_TAG = "tag:yaml.org,2002:"


#: Longest key an error message repeats whole in a dotted field: a name of a
#: sweep's variants may have 100 characters (``experiments.study.NAME_PATTERN``).
_SHOWN_KEY_CHARACTERS = 100


def _unprintable(text: str) -> str | None:
    """The first character of ``text`` that a YAML file may not hold (a control
    character other than tab and line breaks, DEL, a lone surrogate, U+FFFE/U+FFFF),
    as ``U+XXXX``, or None. A quoted scalar's escapes (``"\\0"``, ``"\\ud800"``)
    can make them, which the YAML reader refuses in the file's text."""
    import yaml

    match = yaml.reader.Reader.NON_PRINTABLE.search(text)
    return None if match is None else f"U+{ord(match.group()):04X}"


def _key_shown(key: str) -> str:
    """A mapping key as a dotted field repeats it: its repr if it holds a character
    that does not print on one line, else as written, whole up to
    :data:`_SHOWN_KEY_CHARACTERS` characters (longer: shortened)."""
    if not key.isprintable():
        return shorten(repr(key))
    return key if len(key) <= _SHOWN_KEY_CHARACTERS else shorten(key)


def _check_node(tp, node, field: str, source: str, yaml, tag_checked: bool = False) -> None:
    """:func:`check_node` of one node; ``tag_checked``: its ``!Tag`` chose ``tp`` (an object type)."""

    def fail(message: str, at=node) -> None:
        name = f"{field}: " if field else ""
        raise ScenarioError(f"{source}: line {at.start_mark.line + 1}: {name}{message}")

    def shown(n) -> str:
        if isinstance(n, yaml.MappingNode):
            return "a mapping"
        if isinstance(n, yaml.SequenceNode):
            return "a list"
        if n.tag == "tag:yaml.org,2002:null":
            return "null"
        tag = "" if n.tag in (_STR_TAG, yaml.resolver.Resolver().resolve(yaml.ScalarNode, n.value, (True, False)))\
            else n.tag.replace(_YAML_TAG, "!!") + " "
        return tag + shorten(repr(n.value))

    is_null = isinstance(node, yaml.ScalarNode) and node.tag == "tag:yaml.org,2002:null"
    origin = typing.get_origin(tp)
    if origin is Union:
        args = typing.get_args(tp)
        if type(None) in args and is_null:
            return
        alts = [a for a in args if a is not type(None)]
        if len(alts) == 1:
            return _check_node(alts[0], node, field, source, yaml)
        tags = {f"!{a.__name__}": a for a in alts}
        if node.tag in tags:
            return _check_node(tags[node.tag], node, field, source, yaml, tag_checked=True)
        if node.tag.startswith("!"):
            fail(f"unknown type {node.tag}; allowed: {', '.join(tags)}")
        return _check_node(alts[0], node, field, source, yaml)  # untagged: the first alternative
    # Elsewhere a mapping or list carries no tag (Drake's loader would read a
    # !Tag as an unknown field "_tag", PyYAML's !!set or !!omap as another type).
    default_tag = {yaml.MappingNode: _MAP_TAG, yaml.SequenceNode: _SEQ_TAG}.get(type(node))
    if default_tag is not None and node.tag != default_tag and not tag_checked:
        fail(f"must be {_describe(tp)} without a tag, got {node.tag.replace(_YAML_TAG, '!!')} {shown(node)}")
    if origin is list:
        if not isinstance(node, yaml.SequenceNode):
            fail(f"must be {_describe(tp)}, got {shown(node)}")
        (item,) = typing.get_args(tp)
        for i, child in enumerate(node.value):
            _check_node(item, child, f"{field}[{i}]", source, yaml)
        return
    if origin is dict:
        if not isinstance(node, yaml.MappingNode):
            fail(f"must be {_describe(tp)}, got {shown(node)}")
        key_type, value_type = typing.get_args(tp)
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if (not isinstance(key_node, yaml.ScalarNode) or key_node.tag != "tag:yaml.org,2002:str"
                    or key_node.value == ""):
                raise ScenarioError(f"{source}: line {line}: {field}: names must be non-empty strings, got "
                                    f"{shown(key_node)}")
            sub = f"{field}.{_key_shown(key_node.value)}" if field else _key_shown(key_node.value)
            bad = _unprintable(key_node.value)
            if bad is not None:
                raise ScenarioError(f"{source}: line {line}: {sub}: names must be printable text, got {bad} in "
                                    f"{shown(key_node)}")
            if key_node.value in seen:
                raise ScenarioError(f"{source}: line {line}: {sub}: duplicate key (first at line "
                                    f"{seen[key_node.value]})")
            seen[key_node.value] = line
            _check_node(value_type, value_node, sub, source, yaml)
        return
    if dc.is_dataclass(tp):
        if not isinstance(node, yaml.MappingNode):
            fail(f"must be {_describe(tp)}, got {shown(node)}")
        hints = typing.get_type_hints(tp)  # resolves string annotations (from __future__ import annotations)
        types = {f.name: hints[f.name] for f in dc.fields(tp)}
        seen: dict[str, int] = {}
        for key_node, value_node in node.value:
            line = key_node.start_mark.line + 1
            if not isinstance(key_node, yaml.ScalarNode):
                where = f"{field}: " if field else ""
                raise ScenarioError(f"{source}: line {line}: {where}a key must be a field name ({', '.join(types)}), "
                                    f"got {shown(key_node)}")
            key = key_node.value
            if key_node.tag != _STR_TAG and (key in types or key == ""):  # `!!int random_seed:`, `? !!null`
                where = f"{field}: " if field else ""
                raise ScenarioError(f"{source}: line {line}: {where}a key must be a field name ({', '.join(types)}) "
                                    f"as plain text, without a tag, got {shown(key_node)}")
            sub = f"{field}.{_key_shown(key)}" if field else _key_shown(key)
            if key in seen:  # YAML loaders keep the last silently
                raise ScenarioError(f"{source}: line {line}: {sub}: duplicate key (first at line {seen[key]})")
            seen[key] = line
            if key_node.tag != _STR_TAG or key not in types:
                where = f"in {field}" if field else "at the top level"
                raise ScenarioError(f"{source}: line {line}: {sub}: unknown field {where}; allowed: "
                                    f"{', '.join(types)}")
            _check_node(types[key], value_node, sub, source, yaml)
        return
    if not isinstance(node, yaml.ScalarNode) or is_null:
        fail(f"must be {_describe(tp)}, got {shown(node)}")
    if not node.tag.startswith(_YAML_TAG):  # e.g. `description: !Foo x`
        fail(f"must be {_describe(tp)} without a tag, got {shown(node)}")
    try:  # a standard tag whose text does not fit it (`!!int abc`, `!!bool maybe`), or Python's (`!!python/name:`)
        value = yaml.SafeLoader("").construct_object(node)
    except Exception:
        fail(f"must be {_describe(tp)}, got {shown(node)}")
    if isinstance(value, str) and _unprintable(value) is not None:
        fail(f"must be printable text (the characters a YAML file may hold), got {_unprintable(value)} in "
             f"{shown(node)}")
    if tp is bool:
        ok = isinstance(value, bool)
    elif tp is str:
        ok = isinstance(value, str)
    elif isinstance(value, bool):
        ok = False
    elif tp is int:
        ok = isinstance(value, int) or (isinstance(value, float) and value.is_integer()) or _parses(int, value)
    elif tp is float:
        ok = isinstance(value, (int, float)) or _parses(float, value)
    else:
        ok = True
    if not ok:
        fail(f"must be {_describe(tp)}, got {shown(node)}")


def _parses(kind, value) -> bool:
    if not isinstance(value, str):
        return False
    try:
        kind(value)
    except ValueError:
        return False
    return True
