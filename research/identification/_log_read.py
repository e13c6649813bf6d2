"""Reading the columns of a log file: CSV with a header line, MATLAB ``.mat``, NumPy ``.npz`` and the LinuxCNC
halscope "Save data" text export (``.txt`` / ``.log``). Every failure is a :class:`DriveLogError` naming the
file and, where it applies, the line, column and channel.

Halscope text export (LinuxCNC ``src/hal/utils/scope_files.c``, ``write_log_file``), two generations:

* LinuxCNC 2.9 and later: line 1 ``# Sampling period is <ns> ns``, line 2 the channel names (HAL pins or
  signals) separated by ``;``, optional ``# Position: ...`` and ``# Scale: ...`` display lines, then one row
  per sample of ``;``-separated values (``%.14f``).
* LinuxCNC 2.8 and earlier: line 1 ``Sampling period is <ns> nSec``, then one row per sample of
  whitespace-separated ``<channel> <value>`` pairs (``%s %+.14f``), with blank lines between.

Neither carries a time column: the reader adds ``t = k Ts`` [s] from the header's period (a channel named
``t`` in the file is refused as ambiguous). Bit, s32 and u32 channels are written as numbers and read as
such. The 2.8 writer's loop runs to ``n <= samples`` and so writes one row past the capture; the reader does
not guess which row that is (nothing is dropped silently): cut the log with :meth:`DriveLog.window` if its
last sample is off.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from research.errors import DriveLogError

#: file suffixes read as a halscope text export
HALSCOPE_SUFFIXES = (".txt", ".log")
#: every suffix a log may have
SUFFIXES = (".csv", ".mat", ".npz") + HALSCOPE_SUFFIXES
#: name of the time column the halscope reader adds [s]
HALSCOPE_TIME = "t"

_PERIOD_NEW = re.compile(r"^#\s*Sampling period is\s+(\S+)\s+ns\s*$")
_PERIOD_OLD = re.compile(r"^Sampling period is\s+(\S+)\s+nSec\s*$")


def _numeric(value, where: str) -> np.ndarray:
    """``value`` as a float64 array; a non-numeric (text, object, complex, structured) one is a DriveLogError."""
    a = np.asarray(value) if not isinstance(value, np.ndarray) else value
    if a.dtype.kind not in "iuf":
        raise DriveLogError(f"{where} holds {a.dtype} data ({a.dtype.kind!r} kind); expected real numbers")
    return np.asarray(a, dtype=np.float64)


def _read_table(path: Path) -> dict[str, np.ndarray]:
    """All columns of a CSV (header line), ``.mat``, ``.npz`` or halscope text file as arrays by name.

    Raises:
        DriveLogError: the file cannot be parsed (corrupt or empty archive, non-UTF-8 or ragged text, a
            non-numeric cell: named by line and column), or holds no columns.
    """
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise DriveLogError(f"{path}: unknown drive-log file type {suffix!r}; expected one of {SUFFIXES} "
                            "(.txt / .log: a LinuxCNC halscope text export)")
    try:
        size = path.stat().st_size
    except OSError as e:
        raise DriveLogError(f"{path}: cannot read ({e.strerror or e})") from None
    if size == 0:
        raise DriveLogError(f"{path}: the file is empty; expected a {suffix} drive log")
    if suffix == ".csv":
        raw = _read_csv(path)
    elif suffix in HALSCOPE_SUFFIXES:
        raw = read_halscope(path)
    else:
        try:  # third-party parsers raise many types on damaged bytes; every one becomes a DriveLogError
            if suffix == ".mat":
                from scipy.io import loadmat

                raw = {k: v for k, v in loadmat(str(path)).items() if not k.startswith("__")}
            else:
                with np.load(path, allow_pickle=False) as z:
                    raw = {k: z[k] for k in z.files}
        except MemoryError:
            raise
        except Exception as e:  # noqa: BLE001 - re-raised as this package's error, naming the file
            kind = "MATLAB .mat" if suffix == ".mat" else "NumPy .npz"
            raise DriveLogError(f"{path}: not a readable {kind} file ({type(e).__name__}: {e})") from None
    if not raw:
        raise DriveLogError(f"{path}: the file holds no columns; expected t, x_ref, x_act (or the names you pass)")
    return raw


def _text_lines(path: Path, what: str) -> list[str]:
    try:
        data = path.read_bytes()
    except OSError as e:
        raise DriveLogError(f"{path}: cannot read ({e.strerror or e})") from None
    try:
        return data.decode("utf-8-sig").splitlines()  # a byte-order mark (spreadsheet exports) is not text
    except UnicodeDecodeError as e:
        line = data[: e.start].count(b"\n") + 1
        raise DriveLogError(f"{path}:{line}: not UTF-8 text (byte {data[e.start]:#04x}); save the log as UTF-8 "
                            f"{what}") from None


def _number(cell: str, path: Path, lineno: int, col: int, name: str, decimal_comma: bool = False) -> float:
    try:
        return float(cell.replace(",", ".") if decimal_comma else cell)
    except ValueError:
        raise DriveLogError(f"{path}:{lineno}:{col}: column {name!r}: {cell.strip()!r} is not a number; expected a "
                            "plain decimal number") from None


def _rows(lines, first_lineno: int, sep: str, names, path: Path, expected: str,
          decimal_comma: bool = False) -> list[list[float]]:
    """Numbers of the delimited rows ``lines`` (the first is line ``first_lineno`` of the file); blank and
    ``#`` lines are skipped; a row of another length raises, its message ending with ``expected``.
    ``decimal_comma``: a comma in a number is read as a point (``0,5`` = 0.5)."""
    rows = []
    for lineno, line in enumerate(lines, start=first_lineno):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        cells = line.split(sep)
        if len(cells) != len(names):
            raise DriveLogError(f"{path}:{lineno}: row has {len(cells)} values but {expected}")
        rows.append([_number(c, path, lineno, i, names[i - 1], decimal_comma) for i, c in enumerate(cells, start=1)])
    return rows


def _read_csv(path: Path) -> dict[str, np.ndarray]:
    lines = _text_lines(path, "CSV")
    header = lines[0].strip() if lines else ""
    # the separator is the one of ',', ';' and tab that the header line uses most (',' if none)
    sep = max((",", ";", "\t"), key=lambda c: (header.count(c), c == ","))
    names = [h.strip() for h in header.split(sep)]
    if not header or any(not n for n in names):
        raise DriveLogError(f"{path}:1: a CSV drive log needs a header line naming every column, got {header!r}")
    _unique(names, path, 1)
    # with ';' or a tab as the separator, a decimal comma (the CSV of spreadsheets in locales that write one)
    rows = _rows(lines[1:], 2, sep, names, path, f"the header names {len(names)} columns {names}", sep != ",")
    if not rows:
        raise DriveLogError(f"{path}: the CSV has a header {names} but no data rows")
    data = np.array(rows, dtype=np.float64)
    return {n: data[:, i] for i, n in enumerate(names)}


def _unique(names, path, lineno):
    dup = next((n for i, n in enumerate(names) if n in names[:i]), None)
    if dup is not None:
        raise DriveLogError(f"{path}:{lineno}: column name {dup!r} appears twice; names must be unique")


def _period_s(match, path: Path) -> float:
    try:
        ns = int(match.group(1))
    except ValueError:
        raise DriveLogError(f"{path}:1: halscope sample period {match.group(1)!r} is not an integer number of "
                            "ns") from None
    if ns <= 0:
        raise DriveLogError(f"{path}:1: halscope sample period {ns} ns must be > 0")
    return ns * 1e-9


def read_halscope(path) -> dict[str, np.ndarray]:
    """The channels of a halscope "Save data" text file (module docstring) by name, plus ``t`` [s].

    Args:
        path: ``.txt`` / ``.log`` file written by halscope (either generation).
    Returns:
        channel name -> ``(N,)`` values as written (no unit conversion), and ``"t"`` -> ``k Ts`` [s].
    Raises:
        DriveLogError: first line not a halscope sample-period line, no channels or no samples, a row with
            too few or too many values (a truncated file: the line is named), a non-number (line, column and
            channel named), a legacy row whose channel names differ from the first row's, a channel named ``t``.
    """
    path = Path(path)
    lines = _text_lines(path, "text")
    first = lines[0].strip() if lines else ""
    new, old = _PERIOD_NEW.match(first), _PERIOD_OLD.match(first)
    if not (new or old):
        raise DriveLogError(f"{path}:1: not a halscope text export: the first line is {first[:60]!r}; expected "
                            "'# Sampling period is <ns> ns' (LinuxCNC 2.9+) or 'Sampling period is <ns> nSec' (2.8); "
                            "a CSV log needs the .csv suffix")
    Ts = _period_s(new or old, path)
    names, rows = (_halscope_new if new else _halscope_old)(lines, path)
    if not rows:
        raise DriveLogError(f"{path}: the halscope file names channels {names} but holds no samples")
    if HALSCOPE_TIME in names:
        raise DriveLogError(f"{path}: a halscope channel is named {HALSCOPE_TIME!r}, the name of the time column "
                            "the reader adds from the sample period; rename the channel")
    data = np.array(rows, dtype=np.float64)
    out = {n: data[:, i] for i, n in enumerate(names)}
    out[HALSCOPE_TIME] = np.arange(data.shape[0]) * Ts
    return out


def _halscope_new(lines, path):
    if len(lines) < 2 or not lines[1].strip():
        raise DriveLogError(f"{path}:2: halscope export without its channel-name line (names separated by ';')")
    names = [n.strip() for n in lines[1].split(";")]
    if any(not n for n in names):
        raise DriveLogError(f"{path}:2: empty channel name in {lines[1]!r}")
    _unique(names, path, 2)
    # '#' lines here are halscope's '# Position:' / '# Scale:' display settings
    return names, _rows(lines[2:], 3, ";", names, path, f"line 2 names {len(names)} channels {names}; is the file truncated?")


def _halscope_old(lines, path):
    names, rows = None, []
    for lineno, line in enumerate(lines[1:], start=2):
        tokens = line.split()
        if not tokens:
            continue
        if len(tokens) % 2:
            raise DriveLogError(f"{path}:{lineno}: {len(tokens)} tokens; a halscope 2.8 row is '<channel> <value>' "
                                "pairs; is the file truncated?")
        row_names = tokens[0::2]
        if names is None:
            names = row_names
            _unique(names, path, lineno)
        elif row_names != names:
            raise DriveLogError(f"{path}:{lineno}: channels {row_names} differ from the first row's {names}; is the "
                                "file truncated or were two captures joined?")
        rows.append([_number(v, path, lineno, 2 * i + 2, names[i]) for i, v in enumerate(tokens[1::2])])
    return names or [], rows


def write_halscope(path, channels: dict, sample_period_s: float, *, legacy: bool = False) -> Path:
    """Write ``channels`` (name -> ``(N,)``) as a halscope text export, in the format of LinuxCNC 2.9+ or, with
    ``legacy``, 2.8 (module docstring); for tests and for converting logs. The period is rounded to whole ns."""
    path = Path(path)
    names = list(channels)
    data = np.column_stack([np.asarray(channels[n], dtype=np.float64) for n in names])
    ns = int(round(sample_period_s * 1e9))
    if legacy:
        body = "".join("\n" + "".join(f"{n} {v:+.14f} " for n, v in zip(names, row)) for row in data)
        text = f"Sampling period is {ns} nSec \n{body}\n"
    else:
        rows = "\n".join(";".join(f"{v:.14f}" for v in row) for row in data)
        text = (f"# Sampling period is {ns} ns\n{';'.join(names)}\n# Position: {';'.join(['0.500000'] * len(names))}\n"
                f"# Scale: {';'.join(['0'] * len(names))}\n{rows}\n")
    path.write_text(text, encoding="utf-8")
    return path
