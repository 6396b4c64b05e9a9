"""A walk over MAT v5 variables that refuses, before scipy reads them, the files that would crash scipy."""

from __future__ import annotations

import struct
import zlib

from .. import budget as _budget
from ..errors import FileFormatError

#: Data-type codes scipy's MAT v5 reader has a dtype for; any other code on a numeric or char element makes
#: it dereference a NULL or wild pointer (a segfault: scipy/scipy#25349, unfixed in scipy 1.17).
_MAT_DTYPE_CODES = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 16, 17, 18})
_MAT_MATRIX, _MAT_COMPRESSED = 14, 15
_MAT_CELL, _MAT_STRUCT, _MAT_CHAR = 1, 2, 4
_MAT_NUMERIC_CLASSES = range(6, 16)
#: Largest nesting of cells and structs read, and largest inflated size of one compressed variable.
_MAT_MAX_DEPTH = 32
_MAT_MAX_INFLATED = 1 << 31


class _Mat5Walk:
    """Walks one MAT v5 variable the way scipy's reader will read it, refusing what would crash it.

    scipy reads the elements of a matrix sequentially by class (it does not honour the byte counts of
    nested matrices), so the walk follows the same order: a matrix tag, the array-flags element, the
    dimensions, the name, then per class the numeric parts, the char data, the cells or the struct's
    field names and fields.  Only the classes this library reads (numeric, char, cell, struct) are
    allowed in the variables it loads.
    """

    def __init__(self, buf: bytes, order: str, where: str) -> None:
        self.buf, self.order, self.where, self.pos = buf, order, where, 0

    def fail(self, what: str) -> FileFormatError:
        return FileFormatError(f"{self.where}: not a readable MAT file ({what})")

    def pair(self) -> tuple[int, int]:
        if self.pos + 8 > len(self.buf):
            raise self.fail("truncated")
        a, b = struct.unpack_from(self.order + "II", self.buf, self.pos)
        self.pos += 8
        return int(a), int(b)

    def element(self) -> tuple[int, bytes]:
        """One data element (full or small format): its type code and data."""
        start = self.pos
        word, count = self.pair()
        if word >> 16:  # small data element: the data sit in the tag
            if word >> 16 > 4:
                raise self.fail("bad small data element")
            return word & 0xFFFF, self.buf[start + 4 : start + 4 + (word >> 16)]
        if self.pos + count > len(self.buf):
            raise self.fail("truncated element")
        data = self.buf[self.pos : self.pos + count]
        self.pos += count + (-count % 8)
        return word, data

    def int32s(self, limit: int) -> list[int]:
        code, data = self.element()
        if code not in (5, 6) or len(data) > limit:
            raise self.fail("bad dimensions")
        return list(struct.unpack_from(f"{self.order}{len(data) // 4}i", data))

    def header(self) -> tuple[int, bool, list[int], str]:
        """After a matrix tag: array flags, dimensions and name (class, complex, dims, name)."""
        self.pair()  # the array-flags tag, not checked by scipy
        flags, _ = self.pair()
        mclass, is_complex = flags & 0xFF, bool(flags >> 11 & 1)
        dims = [] if mclass == 17 else self.int32s(128)
        code, name = self.element()
        if code not in (1, 16) or len(dims) > 32:
            raise self.fail("bad array name or dimensions")
        return mclass, is_complex, dims, name.decode("latin1")

    def matrix(self, depth: int) -> None:
        """A nested matrix (a cell or a struct field)."""
        code, count = self.pair()
        if code != _MAT_MATRIX:
            raise self.fail(f"element type {code} where a matrix is expected")
        if count:
            mclass, is_complex, dims, _ = self.header()
            self.array(mclass, is_complex, dims, depth + 1)

    def count(self, dims: list[int], per_item: int) -> int:
        n = 1
        for d in dims:
            if d < 0:
                raise self.fail("negative dimension")
            n *= d
        # Every cell or field is a matrix of at least 8 bytes; a struct without fields reads nothing per
        # element, but scipy still loops over them.
        if n * per_item * 8 > len(self.buf) - self.pos or (per_item == 0 and n > 10**6):
            raise self.fail("more elements than the data can hold")
        return n

    def array(self, mclass: int, is_complex: bool, dims: list[int], depth: int) -> None:
        if depth > _MAT_MAX_DEPTH:
            raise self.fail("cells or structs nested too deep")
        if len(dims) < 2:  # MATLAB arrays have 2 or more; scipy's char conversion crashes on 0
            raise self.fail(f"an array with {len(dims)} dimensions")
        if mclass in _MAT_NUMERIC_CLASSES or mclass == _MAT_CHAR:
            for _ in range(2 if is_complex and mclass != _MAT_CHAR else 1):
                code, data = self.element()
                # scipy looks the code up even for no data, except in char arrays.
                if (data or mclass != _MAT_CHAR) and code not in _MAT_DTYPE_CODES:
                    raise self.fail(f"unknown data type code {code}")
        elif mclass == _MAT_CELL:
            for _ in range(self.count(dims, 1)):
                self.matrix(depth)
        elif mclass == _MAT_STRUCT:
            (length,) = self.int32s(4) or [0]
            code, names = self.element()
            if code not in (1, 16) or length <= 0:
                raise self.fail("bad struct field names")
            fields = len(names) // length
            for _ in range(self.count(dims, fields) * fields):
                self.matrix(depth)
        else:
            raise self.fail(f"MATLAB class {mclass} (objects, sparse, function handles) is not supported")


def _guard_mat5(data: bytes, wanted: set[str], where: str) -> None:
    """Refuse a MAT v5 file whose variables in ``wanted`` would crash scipy's reader; leave every other
    fault (and v4 and v7.3 files) to scipy, which raises on them."""
    if len(data) < 128 or 0 in data[:4]:
        return
    version = data[124:128]
    if version[int(version[2] == ord("I"))] != 1:
        return
    order = "<" if data[126:128] == b"IM" else ">"
    pos = 128
    inflated_total = 0
    while pos < len(data):
        top = _Mat5Walk(data, order, where)
        top.pos = pos
        code, count = top.pair()
        if count == 0:
            return  # scipy refuses it
        pos = top.pos + count
        if code == _MAT_COMPRESSED:
            inflater = zlib.decompressobj()
            try:
                limit = min(_MAT_MAX_INFLATED, _budget.get_budget().max_bytes - inflated_total)
                inflated = inflater.decompress(data[top.pos : pos], max(limit, 0) + 1)
            except zlib.error as exc:
                raise top.fail(f"corrupt compressed variable: {exc}") from exc
            if inflater.unconsumed_tail or len(inflated) > limit:
                if limit < _MAT_MAX_INFLATED:
                    _budget.check_bytes(
                        f"{where}: the compressed variables of the MAT file", inflated_total + len(inflated)
                    )
                raise top.fail("a compressed variable inflates beyond 2 GiB")
            inflated_total += len(inflated)
            # At least one byte per element (8 for the float64 signals): an upper bound of the samples.
            _budget.check_samples(f"{where}: a compressed variable of the MAT file", len(inflated) // 8)
            walk = _Mat5Walk(inflated, order, where)
            code, count = walk.pair()
        else:
            walk = top
        if code != _MAT_MATRIX:
            return  # scipy refuses it
        if count == 0:
            continue
        mclass, is_complex, dims, name = walk.header()
        if name in wanted:
            walk.array(mclass, is_complex, dims, 0)
