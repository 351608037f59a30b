"""Results streamed to a file as they are computed (``Model.run(stream=...)``), and read back.

A path ending in ``.csv`` is written by the engine itself (the bytes of ``results.csv``); one
ending in ``.parquet`` by :class:`ParquetSink`, a row group per chunk of rows (needs pyarrow:
``pip install 'linkwork[parquet]'``).
"""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any

import numpy as np

SUFFIXES = (".csv", ".parquet")


class ParquetSink:
    """The engine's sink for a Parquet file: ``begin(names)``, ``write(time, values)`` for each
    chunk (a row group: a ``time`` column, then one float64 column per name), ``finish()``."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        try:
            import pyarrow  # noqa: F401
        except ImportError as error:
            raise ImportError("streaming to Parquet needs pyarrow: pip install 'linkwork[parquet]'") from error
        self.path = os.fspath(path)
        self._names: list[str] = []
        self._writer: Any = None

    def begin(self, names: list[str]) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        self._names = ["time", *names]
        schema = pa.schema([(name, pa.float64()) for name in self._names])
        self._writer = pq.ParquetWriter(self.path, schema)

    def write(self, time: np.ndarray, values: np.ndarray) -> None:
        import pyarrow as pa

        arrays = [pa.array(time), *(pa.array(values[:, k]) for k in range(values.shape[1]))]
        self._writer.write_table(pa.Table.from_arrays(arrays, names=self._names))

    def finish(self) -> None:
        if self._writer is not None:
            self._writer.close()


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
    ``ValueError``."""
    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        columns = {name: table.column(name).to_numpy() for name in table.column_names}
        return columns.pop("time"), columns
    with open(path, encoding="utf-8", newline="") as file:
        rows = list(csv.reader(file))
    header, body = rows[0], rows[1:]
    values = np.array(body, dtype=float).reshape(len(body), len(header))
    time = values[:, header.index("time")]
    return time, {name: values[:, k] for k, name in enumerate(header) if name != "time"}
