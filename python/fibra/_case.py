"""Cases: read from TOML or JSON case files, or built from Python dicts (the same keys)."""

import copy
import json
import math
import os
import re
import tomllib

from . import _fibra

_INDEX = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\[(\d+)\]$")


def _input_error(file, key, message):
    error = _fibra.InputError(f"{file}: {key}: {message}")
    error.file = file
    error.key = key
    return error


def _plain(value, key, label):
    """`value` as plain JSON data: numpy numbers and arrays become floats, ints and lists;
    anything else that JSON cannot hold, or a number that is not finite, is an InputError
    naming its key."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise _input_error(label, key or "(case)", f"keys are strings, got {k!r}")
            if v is not None:  # a key set to None is left out
                out[k] = _plain(v, f"{key}.{k}" if key else k, label)
        return out
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{key}[{i}]", label) for i, v in enumerate(value)]
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):  # numpy scalars, arrays
        return _plain(value.tolist(), key, label)
    if value is None:
        raise _input_error(label, key, "None in a list: leave the item out")
    if isinstance(value, bool) or isinstance(value, str):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            raise _input_error(label, key, f"expected a finite number, got {value}")
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise _input_error(label, key, f"expected a number, string, boolean, list or dict, got {type(value).__name__}")


def _without_none(value):
    """`value` with the keys set to None left out (TOML has no null)."""
    if isinstance(value, dict):
        return {k: _without_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, list):
        return [_without_none(v) for v in value]
    return value


def _set(data, dotted, value):
    """Sets `data` at a key path such as "fabric.warp.spacing" or "step[2].strain"; missing
    tables are made, a missing list item is an error."""
    parts = dotted.split(".")
    node = data
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        m = _INDEX.match(part)
        if m:
            name, index = m.group(1), int(m.group(2))
            items = node.get(name)
            if not isinstance(items, list) or index >= len(items):
                count = len(items) if isinstance(items, list) else 0
                raise KeyError(f"{dotted}: the case has {count} `{name}` item(s), no [{index}]")
            if last:
                items[index] = value
            else:
                if not isinstance(items[index], dict):
                    raise KeyError(f"{dotted}: `{name}[{index}]` is not a table")
                node = items[index]
        elif last:
            node[part] = value
        else:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise KeyError(f"{dotted}: `{part}` is not a table")
            node = child


class Case:
    """A validated case.

    Case(data, name="case") checks a dict of the case file's tables and keys (the schema of
    docs/case-file.md: `{"material": [{...}], "fabric": {...}, "step": [{...}]}`); a problem
    raises InputError with the key path (`fabric.warp.spacing`), as for a file. Numbers may be
    numpy numbers. `name` names the default output directory, out/<name>.
    """

    def __init__(self, data, name="case", *, _handle=None, _file=None):
        if not isinstance(data, dict):
            raise TypeError(f"a case is a dict of its tables and keys, got {type(data).__name__}")
        if not isinstance(name, str) or not name or "/" in name or name in (".", ".."):
            raise ValueError(f"name: expected a non-empty name for out/<name>, without '/', got {name!r}")
        self._file = _file
        if _handle is None:
            label = "<dict>"
            self._data = _plain(data, "", label)
            self._handle = _fibra.parse_case(json.dumps(self._data), True, label, name)
        else:
            self._data = copy.deepcopy(data)
            self._handle = _handle

    @classmethod
    def load(cls, path):
        """Reads and checks a case file (.toml or .json), as `fibra check` does."""
        path = os.fspath(path)
        handle = _fibra.read_case(path)
        with open(path, "rb") as f:
            text = f.read().decode("utf-8-sig")
        try:
            data = json.loads(text) if path.lower().endswith(".json") else tomllib.loads(text)
        except ValueError as e:  # the reader above accepted it: a difference of the parsers
            raise _input_error(path, "(file)", f"Python cannot parse what fibra read: {e}") from None
        start = data.get("start")
        if isinstance(start, dict) and isinstance(start.get("from"), str) and not os.path.isabs(start["from"]):
            # Taken from the file's directory (docs/case-file.md): made absolute, so that the
            # case's dict, a case derived from it and the TOML it writes elsewhere go on from
            # the same run.
            start["from"] = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), start["from"]))
        return cls(data, _handle=handle, _file=path)

    # -- what it holds ----------------------------------------------------------------------
    @property
    def name(self):
        """Names the default output directory, out/<name> (a file's stem)."""
        return self._handle.name

    @property
    def title(self):
        return self._handle.title

    @property
    def file(self):
        """The case file it was read from, or None for a case built from a dict."""
        return self._file

    @property
    def steps(self):
        """The steps: a list of dicts with "name", "kind" and "increments"."""
        return self._handle.steps

    @property
    def tows(self):
        """The names of the tows (a [fabric]'s included)."""
        return self._handle.tows

    def check(self):
        """Builds the model as a run would (every reference resolved) and returns its counts:
        materials, fibers, nodes, dofs, steps, tows, bodies."""
        return self._handle.check()

    # -- as data and as text ----------------------------------------------------------------
    def to_dict(self):
        """The case's tables and keys, as written (a [fabric] not expanded); a copy."""
        return copy.deepcopy(self._data)

    def to_toml(self, expanded=False):
        """The case as a TOML case file. expanded=True writes the assembly the reader made
        (a [fabric] expanded into its fibers, bodies, bindings and tows) instead."""
        if expanded:
            return self._handle.expanded_toml()
        import tomli_w  # python3-tomli-w
        return tomli_w.dumps(_without_none(self._data))

    def write(self, path, expanded=False):
        """Writes the case as a TOML file (see to_toml) and returns its path."""
        path = os.fspath(path)
        with open(path, "w", encoding="utf-8") as f:
            f.write(self.to_toml(expanded))
        return path

    def with_values(self, values=None, name=None, **keys):
        """A new case with some keys set, by key path, e.g.
        case.with_values({"fabric.warp.spacing": 0.4e-3, "step[2].strain": 0.02}) or
        case.with_values(title="denser"). Checked like any case."""
        data = copy.deepcopy(self._data)
        for key, value in {**(values or {}), **keys}.items():
            if not isinstance(key, str):
                raise TypeError(f"a key path is a string such as \"fabric.warp.spacing\", got {key!r}")
            _set(data, key, value)
        return Case(data, name=name or self.name)

    def __repr__(self):
        steps = ", ".join(f"{s['name']} ({s['kind']})" for s in self.steps)
        where = f" from {self._file}" if self._file else ""
        return f"<fibra.Case {self.name!r}{where}: steps {steps}>"


def case_keys(table=None):
    """The keys a case file (or a case dict) may hold, as the reader declares them (the tables
    of docs/case-file.md): {table: [{"name", "type", "default", "allowed", "unit", "meaning",
    "variant", "choices", "expected"}, ...]}, tables named by their path without indices ("top", "fiber",
    "fabric.tow", "step.load", ...); with `table`, that table's list alone."""
    tables = _fibra.schema()
    if table is None:
        return tables
    if table not in tables:
        raise KeyError(f"no table {table!r}; the tables: {', '.join(tables)}")
    return tables[table]


def load_case(path):
    """Reads and checks a case file (.toml or .json): a Case."""
    return Case.load(path)
