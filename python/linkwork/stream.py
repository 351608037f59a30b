"""Results streamed to a file as they are computed (``Model.run(stream=...)``), and read back.

A path ending in ``.csv`` is written by the engine itself (the bytes of ``results.csv``); one
ending in ``.parquet`` by :class:`ParquetSink`, a row group per chunk of rows (needs pyarrow:
``pip install 'linkwork[parquet]'``).
"""

from __future__ import annotations

import csv
import io
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np

SUFFIXES = (".csv", ".parquet")


class ParquetSink:
    """The engine's sink for a Parquet file: ``begin(names)``, ``write(time, values)`` for each
    chunk (a row group: a ``time`` column, then one float64 column per name), ``finish()``.

    A Parquet file is readable only once its footer is written, at its end. So that a run killed
    part-way leaves rows a reader can open, each chunk is first a complete Parquet file of its
    own in the folder :func:`parts` names beside ``path`` (written whole, then renamed into
    place); ``finish()`` copies them into ``path``, a row group each (written whole, then renamed
    over any file there), and removes them. :func:`read` reads the parts of a file that was
    never finished."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        try:
            import pyarrow  # noqa: F401
        except ImportError as error:
            raise ImportError("streaming to Parquet needs pyarrow: pip install 'linkwork[parquet]'") from error
        self.path = os.fspath(path)
        self._names: list[str] = []
        self._parts = parts(path)
        self._written = 0

    def begin(self, names: list[str]) -> None:
        self._names = ["time", *names]
        shutil.rmtree(self._parts, ignore_errors=True)
        self._parts.mkdir()
        # A first part with no row: the columns are known from the start.
        self.write(np.empty(0), np.empty((0, len(names))))

    def write(self, time: np.ndarray, values: np.ndarray) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        arrays = [pa.array(time, pa.float64()), *(pa.array(values[:, k], pa.float64()) for k in range(values.shape[1]))]
        part = self._parts / f"{self._written:08d}.parquet"
        temp = part.with_name(f".{part.name}.tmp")
        pq.write_table(pa.Table.from_arrays(arrays, names=self._names), temp)
        os.replace(temp, part)
        self._written += 1

    def finish(self) -> None:
        import pyarrow.parquet as pq

        if not self._names:
            return
        path = Path(self.path)
        temp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            chunks = _parts_of(self._parts)
            with pq.ParquetWriter(temp, pq.read_schema(chunks[0])) as writer:
                for chunk in chunks:
                    table = pq.read_table(chunk)
                    if table.num_rows:
                        writer.write_table(table)
            os.replace(temp, path)
        finally:
            temp.unlink(missing_ok=True)
        shutil.rmtree(self._parts, ignore_errors=True)


def parts(path: str | os.PathLike[str]) -> Path:
    """The folder of the chunks of the Parquet file at ``path`` while it is streamed
    (``.<name>.parts`` beside it), each a Parquet file of its own, numbered in order."""
    path = Path(path)
    return path.with_name(f".{path.name}.parts")


def _parts_of(folder: Path) -> list[Path]:
    """The complete chunks in ``folder``, in order (a chunk still being written has another name)."""
    return sorted(folder.glob("[0-9]*.parquet"))


def sink(path: str | os.PathLike[str]) -> str | ParquetSink:
    """What the engine streams to for ``path``: the path itself for CSV, a :class:`ParquetSink`
    for Parquet. Any other suffix is a ``ValueError``."""
    path = Path(path)
    if path.suffix == ".csv":
        return os.fspath(path)
    if path.suffix == ".parquet":
        return ParquetSink(path)
    raise ValueError(f"expected a path ending in .csv or .parquet, got '{path}'")


def read(path: str | os.PathLike[str]) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The times and the columns (by name, ``time`` left out) of a results file, CSV (the
    format of ``results.csv``) or Parquet. An unreadable file raises ``OSError`` or
    ``ValueError``.

    A stream that was killed is read up to its last complete row: a CSV file's last line
    without its line end (cut short by the kill) is left out, and a Parquet file that was never
    finished is read from its chunks (:func:`parts`)."""
    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        chunks = _parts_of(parts(path)) if not path.exists() else []
        table = pa.concat_tables([pq.read_table(c) for c in chunks]) if chunks else pq.read_table(path)
        columns = {name: table.column(name).to_numpy() for name in table.column_names}
        return columns.pop("time"), columns
    with open(path, encoding="utf-8", newline="") as file:
        text = file.read()
    # Whole lines only: a line without its end was cut short.
    rows = list(csv.reader(io.StringIO(text[: text.rfind("\n") + 1])))
    if not rows:
        raise ValueError(f"{path}: no header line")
    header, body = rows[0], rows[1:]
    values = np.array(body, dtype=float).reshape(len(body), len(header))
    time = values[:, header.index("time")]
    return time, {name: values[:, k] for k, name in enumerate(header) if name != "time"}
