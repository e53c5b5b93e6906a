"""hystloop.read_export: the files hystloop-export writes (HDF5, MAT level 5, MAT 7.3), read back
into the shape hystloop.read_log gives (docs/EXPORT.md has the layouts): one ExportChannel per
channel, its columns as numpy arrays (float64, int64, object for texts; a ragged column as a list
of one array per row) with their units, descriptions and legends; HX_STATUS's counters by name.
h5py reads HDF5 and MAT 7.3, scipy.io MAT level 5 (Debian: python3-h5py, python3-scipy)."""

import os

import numpy as np

_HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"
_META = ("channel", "lcm_type", "rows", "events", "skipped_events", "units", "description", "legend", "ragged")


class ExportChannel:
    """One channel of an export, as hystloop.Channel: name, type_name, rows, events, skipped,
    columns, units, descriptions, legends, counters (HX_STATUS); channel["y_m"] is a column."""

    def __init__(self, name, type_name, rows, events, skipped, columns, units, descriptions, legends):
        self.name, self.type_name = name, type_name
        self.rows, self.events, self.skipped = rows, events, skipped
        self.columns, self.units, self.descriptions, self.legends = columns, units, descriptions, legends
        self.counters = _counters(columns, rows) if type_name == "hystloop.service_status_t" else {}

    def __getitem__(self, column):
        return self.columns[column]

    def __contains__(self, column):
        return column in self.columns

    def __len__(self):
        return self.rows

    def keys(self):
        return self.columns.keys()

    def __repr__(self):
        return f"hystloop.ExportChannel({self.name}, {self.type_name}, {self.rows} rows: {', '.join(self.columns)})"


class Export:
    """What read_export read: path, format ("hdf5", "mat5" or "mat7.3"), channels (name ->
    ExportChannel, as exported), run (the run's attributes: rig_prefix, time_zero_utime_us,
    logs, ...), config (file name -> text of each --config file); export["SENSOR"] or
    export["HX_SENSOR"] is a channel."""

    def __init__(self, path, fmt, channels, run, config):
        self.path, self.format, self.channels, self.run, self.config = path, fmt, channels, run, config
        self.prefix = str(run.get("rig_prefix", "HX_"))

    def __getitem__(self, channel):
        if channel in self.channels:
            return self.channels[channel]
        if self.prefix + channel in self.channels:
            return self.channels[self.prefix + channel]
        raise KeyError(f"no channel '{channel}' exported (channels: {', '.join(self.channels) or 'none'})")

    def __contains__(self, channel):
        return channel in self.channels or self.prefix + channel in self.channels

    def __repr__(self):
        return f"hystloop.Export({self.path}, {self.format}: {', '.join(self.channels)})"


def _counters(columns, rows):
    """HX_STATUS's counters by name, one float64 per row (NaN where a row lacks it), as read_log."""
    names, values = columns.get("counter_names"), columns.get("counter_values")
    if names is None or values is None or "n_counters" not in columns:
        return {}
    out = {}
    for r in range(rows):
        for name, value in zip(names[r], values[r]):
            if name not in out:
                out[name] = np.full(rows, np.nan)
            out[name][r] = float(value)
    return out


def _split_rows(flat, counts):
    """A ragged column's values, one array per row (as read_log: a row's part is cut at the end)."""
    out, at = [], 0
    for n in counts:
        n = min(int(n), len(flat) - min(at, len(flat)))
        out.append(flat[at : at + n])
        at += n
    return out


def _column_of(flat, rows, count_column, per_row, columns):
    if count_column:
        return _split_rows(flat, columns[count_column])
    if per_row:
        return _split_rows(flat, [int(per_row)] * rows)
    return flat


def _ragged_of(text):
    """The meta's ragged entry: a count column's name or "N per row"."""
    text = str(text)
    if text.endswith(" per row"):
        return None, int(text.split()[0])
    return text, None


# HDF5 (hystloop-export --hdf5) ------------------------------------------------------------------


def _text(v):
    return v.decode("utf-8") if isinstance(v, bytes) else str(v)


def _h5_values(d):
    v = d[...]
    if v.dtype.kind in "OSU":
        return np.array([_text(x) for x in v.ravel()], dtype=object)
    return np.ascontiguousarray(v.ravel())


def _read_hdf5(path, h5py):
    channels, config = {}, {}
    with h5py.File(path, "r") as f:
        run = {k: (_text(v) if isinstance(v, (bytes, str)) else v) for k, v in f.attrs.items()}
        if "config" in f:
            config = {k: _text(f["config"][k][()]) for k in f["config"]}
        for name in f:
            g = f[name]
            if name == "config" or not isinstance(g, h5py.Group) or "lcm_type" not in g.attrs:
                continue
            rows = int(g.attrs["rows"])
            flat, ragged, units, descriptions, legends = {}, {}, {}, {}, {}
            for c in g:
                d = g[c]
                flat[c] = _h5_values(d)
                units[c] = _text(d.attrs["units"]) if "units" in d.attrs else ""
                descriptions[c] = _text(d.attrs["description"]) if "description" in d.attrs else ""
                if "legend" in d.attrs:
                    legends[c] = _text(d.attrs["legend"])
                if "count_column" in d.attrs or "per_row" in d.attrs:
                    ragged[c] = (_text(d.attrs.get("count_column", "")), int(d.attrs.get("per_row", 0)))
            columns = {}
            for c, v in flat.items():
                count_column, per_row = ragged.get(c, ("", 0))
                columns[c] = _column_of(v, rows, count_column, per_row, flat)
            channels[_text(g.attrs["channel"])] = ExportChannel(
                _text(g.attrs["channel"]), _text(g.attrs["lcm_type"]), rows, int(g.attrs["events"]),
                int(g.attrs["skipped_events"]), columns, units, descriptions, legends)
    return channels, run, config


# MAT level 5 (hystloop-export --mat, scipy.io) --------------------------------------------------


def _dict(v):
    return v if isinstance(v, dict) else {}


def _mat5_scalar(v):
    """A scipy.io value as Python: a struct as a dict, a char as str, a number as a scalar."""
    for _ in range(8):  # scipy wraps a struct's fields in 1x1 object arrays
        v = np.asarray(v)
        if v.dtype != object or v.size != 1:
            break
        v = v.ravel()[0]
        if v is None:
            return ""
    v = np.asarray(v)
    if v.dtype.names:
        return {n: _mat5_scalar(v[n].ravel()[0]) if v[n].size else "" for n in v.dtype.names}
    if v.dtype.kind == "U":
        return str(v.ravel()[0]) if v.size else ""
    if v.dtype == object:
        return [_mat5_scalar(x) for x in v.ravel()]
    return v.ravel()[0] if v.size == 1 else v.ravel()


def _mat5_column(v):
    v = np.asarray(v)
    if v.dtype == object:  # a cell of char: one text per row
        return np.array([str(x.ravel()[0]) if x.size else "" for x in v.ravel()], dtype=object)
    return np.ascontiguousarray(v.ravel())


def _read_mat5(path):
    import scipy.io

    m = scipy.io.loadmat(path, mat_dtype=False, squeeze_me=False, chars_as_strings=True)
    run = _mat5_scalar(m["hystloop_run"]) if "hystloop_run" in m else {}
    config = run.pop("config", {}) if isinstance(run, dict) else {}
    channels = {}
    for var in [k for k in m if not k.startswith("__") and k + "_meta" in m]:
        meta = {n: m[var + "_meta"][n][0, 0] for n in m[var + "_meta"].dtype.names}
        s = m[var]
        fields = s.dtype.names or ()
        flat = {n: _mat5_column(s[n][0, 0]) for n in fields}
        units, descriptions, legends, ragged = (
            _dict(_mat5_scalar(meta[k])) if k in meta else {} for k in ("units", "description", "legend", "ragged"))
        rows = int(_mat5_scalar(meta["rows"]))
        columns = {}
        for n in fields:
            count_column, per_row = _ragged_of(ragged[n]) if n in ragged else ("", 0)
            columns[n] = _column_of(flat[n], rows, count_column, per_row, flat)
        name = _mat5_scalar(meta["channel"])
        channels[name] = ExportChannel(name, _mat5_scalar(meta["lcm_type"]), rows, int(_mat5_scalar(meta["events"])),
                                       int(_mat5_scalar(meta["skipped_events"])), columns,
                                       {n: units.get(n, "") for n in fields},
                                       {n: descriptions.get(n, "") for n in fields},
                                       {n: legends[n] for n in fields if n in legends})
    return channels, run if isinstance(run, dict) else {}, config if isinstance(config, dict) else {}


# MAT 7.3 (hystloop-export --mat --mat-version 7.3: HDF5 in MATLAB's layout) ---------------------


def _m73_class(d):
    c = d.attrs.get("MATLAB_class", b"")
    return c.decode() if isinstance(c, bytes) else str(c)


def _m73_char(d):
    if d.attrs.get("MATLAB_empty", 0):
        return ""
    return np.asarray(d[...], dtype=np.uint16).T.ravel().tobytes().decode("utf-16-le")


def _m73_fields(g):
    names = g.attrs.get("MATLAB_fields")
    if names is None:
        return list(g)
    return [b"".join(n).decode() for n in names]


def _m73_value(f, d):
    """A MATLAB value: a struct as a dict, a char as str, a cell of char as an object array of str,
    a numeric array flattened (MATLAB's column vectors are stored transposed)."""
    import h5py

    if isinstance(d, h5py.Group):
        return {n: _m73_value(f, d[n]) for n in _m73_fields(d)}
    cls = _m73_class(d)
    if cls == "struct":  # an empty struct (no field): a dataset of its dimensions
        return {}
    if cls == "char":
        return _m73_char(d)
    if cls == "cell":
        if d.attrs.get("MATLAB_empty", 0):
            return np.zeros(0, dtype=object)
        return np.array([_m73_char(f[r]) for r in d[...].T.ravel()], dtype=object)
    if d.attrs.get("MATLAB_empty", 0):
        return np.zeros(0, dtype=np.float64 if cls == "double" else np.int64)
    return np.ascontiguousarray(d[...].T.ravel())


def _read_mat73(path, h5py):
    with h5py.File(path, "r") as f:
        run = _m73_value(f, f["hystloop_run"]) if "hystloop_run" in f else {}
        config = run.pop("config", {}) if isinstance(run, dict) else {}
        channels = {}
        for var in [k for k in f if not k.startswith("#") and k + "_meta" in f]:
            meta = _m73_value(f, f[var + "_meta"])
            fields = _m73_fields(f[var])
            flat = {n: _m73_value(f, f[var][n]) for n in fields}
            rows = int(np.asarray(meta["rows"]).ravel()[0])
            ragged, columns = _dict(meta.get("ragged")), {}
            for n in fields:
                count_column, per_row = _ragged_of(ragged[n]) if n in ragged else ("", 0)
                columns[n] = _column_of(flat[n], rows, count_column, per_row, flat)
            units, descriptions, legends = (_dict(meta.get(k)) for k in ("units", "description", "legend"))
            number = lambda k: int(np.asarray(meta[k]).ravel()[0])  # noqa: E731
            channels[meta["channel"]] = ExportChannel(
                meta["channel"], meta["lcm_type"], rows, number("events"), number("skipped_events"), columns,
                {n: units.get(n, "") for n in fields}, {n: descriptions.get(n, "") for n in fields},
                {n: legends[n] for n in fields if n in legends})
    return channels, run, config


def read_export(path):
    """read_export(path) -> Export

    Reads a file hystloop-export wrote: HDF5 (--hdf5), MAT level 5 (--mat) or MAT 7.3
    (--mat --mat-version 7.3), told apart by their content. Every channel comes back in the shape
    hystloop.read_log gives it: export["SENSOR"]["y_m"] (float64, bit for bit as logged),
    .units["y_m"] ("m"), .descriptions, .legends, .counters (HX_STATUS); integer columns int64,
    texts object arrays of str, a ragged column (a status's counters, a trajectory's points) a list
    of one array per row. Export.run holds the run's attributes, Export.config the --config files.
    Columns read_log adds that the export does not hold (axis, y_true_m) are not there."""
    path = os.fspath(path)
    with open(path, "rb") as f:
        head = f.read(640)
    if _HDF5_MAGIC in (head[:8], head[512:520]):
        import h5py

        with h5py.File(path, "r") as f:
            is_mat = "hystloop_run" in f and _m73_class(f["hystloop_run"]) == "struct"
        if is_mat:
            return Export(path, "mat7.3", *_read_mat73(path, h5py))
        return Export(path, "hdf5", *_read_hdf5(path, h5py))
    if len(head) >= 128 and head[126:128] in (b"IM", b"MI"):  # a level 5 header's endian indicator
        return Export(path, "mat5", *_read_mat5(path))
    raise ValueError(f"{path}: neither an HDF5 nor a MAT file (hystloop-export writes --hdf5 or --mat)")
