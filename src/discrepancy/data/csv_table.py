"""Reading numeric columns of a CSV table as benchmark files and spreadsheets write them.

Tolerated, because real files have them: a UTF-8 byte order mark, quoted header names,
empty trailing columns (``"a","b",``), blank lines, and columns that are empty in most
rows (a sampling time given in the first row only) as long as they are not asked for.
Refused with the line and column named: duplicated or empty header names, a row with
more filled cells than the header has names or with fewer cells, and a requested cell
that is empty or not a number. Parsing uses the standard ``csv`` module.
"""
from __future__ import annotations

import csv
import itertools
from collections import Counter
from collections.abc import Sequence

import numpy as np

from ..errors import DataError


class CSVTable:
    """A CSV file's header and its numeric columns, read row by row.

    Use as a context manager: ``with CSVTable(path) as table: table.read([0, 2])``.
    """

    def __init__(self, path):
        self.name = getattr(path, "name", str(path))
        self._fh = open(path, newline="", encoding="utf-8-sig")
        self._reader = csv.reader(self._fh)
        self._lines = self._checked_lines()
        try:
            self.header = self._read_header()
            #: column index by name (the lookups stay linear in the number of columns)
            self.position = {name: i for i, name in enumerate(self.header)}
        except BaseException:
            self._fh.close()
            raise

    def __enter__(self) -> CSVTable:
        return self

    def __exit__(self, *exc) -> None:
        self._fh.close()

    def _checked_lines(self):
        """The rows of cells, with undecodable bytes and broken quoting reported as
        DataError naming the line."""
        try:
            yield from self._reader
        except (UnicodeDecodeError, csv.Error) as e:
            raise DataError(f"{self.name} line {self._reader.line_num + 1}: not readable as "
                            f"UTF-8 CSV text ({type(e).__name__}: {e})") from None

    def _read_header(self) -> list[str]:
        for row in self._lines:
            if any(cell.strip() for cell in row):
                header = [cell.strip() for cell in row]
                break
        else:
            raise DataError(f"{self.name}: a CSV file needs a header row and data rows; it is "
                            "empty")
        while header and header[-1] == "":
            header.pop()
        empty = [i for i, h in enumerate(header) if h == ""]
        if empty:
            raise DataError(f"{self.name}: header column {empty[0] + 1} has no name; every "
                            "column needs one")
        repeated = sorted(h for h, k in Counter(header).items() if k > 1)
        if repeated:
            raise DataError(f"{self.name}: the header names {repeated} more than once; column "
                            "names must be unique")
        return header

    def read(self, columns: Sequence[int], max_rows: int | None = None) -> np.ndarray:
        """The values of ``columns`` (indices into ``header``) of the next data rows,
        ``(rows, len(columns))``; at most ``max_rows`` rows (``None``: to the end)."""
        filled = (cells for cells in self._lines if any(cell.strip() for cell in cells))
        values = [self._values(cells, columns) for cells in itertools.islice(filled, max_rows)]
        return np.array(values, dtype=float).reshape(len(values), len(columns))

    def _values(self, cells: list[str], columns: Sequence[int]) -> list[float]:
        n, line = len(self.header), self._reader.line_num
        if len(cells) < n:
            raise DataError(f"{self.name} line {line}: {len(cells)} cells; the header has {n} "
                            "columns")
        if any(cell.strip() for cell in cells[n:]):
            raise DataError(f"{self.name} line {line}: {len(cells)} cells, more than the "
                            f"header's {n} columns (a cell without a column name)")
        out = []
        for j in columns:
            text = cells[j].strip()
            try:
                out.append(float(text))
            except ValueError:
                what = "an empty cell" if text == "" else f"non-numeric value {text[:20]!r}"
                raise DataError(f"{self.name} line {line}, column {self.header[j]!r}: "
                                f"{what}") from None
        return out
