#!/usr/bin/env python3
"""Reads MCAP files with the reference MCAP library (PyPI `mcap`, 1.x) and prints, for each,
`NAME accept` or `NAME refuse: WHY` (NAME: the file name without `.mcap`).

The library reads every record, with the records of every chunk, checking the chunk CRCs and
the data section's CRC (`StreamReader(validate_crcs=True)`). It does not check the summary
section's CRC; that one is checked here from the MCAP specification: the CRC-32 of the bytes
from the summary's start (the Footer's `summary_start`) through the Footer's
`summary_offset_start` field, when it is not 0.

Used by `bag/tests/integrity.rs` to confirm that beamfield's reader refuses and accepts the
same damaged files as the reference. Usage: python3 mcap_reference.py FILE.mcap...
"""

import os
import struct
import sys
import zlib

from mcap.stream_reader import StreamReader

FOOTER_BODY = 20  # summary_start u64, summary_offset_start u64, summary_crc u32
MAGIC_LEN = 8


def summary_crc_problem(data: bytes):
    """Why the summary section's CRC is wrong, or None (also when it is 0 or absent)."""
    footer_at = len(data) - MAGIC_LEN - 9 - FOOTER_BODY
    if footer_at < MAGIC_LEN or data[footer_at] != 0x02:
        return None
    summary_start, _, saved = struct.unpack_from("<QQI", data, footer_at + 9)
    if saved == 0 or summary_start == 0 or summary_start > footer_at:
        return None
    calculated = zlib.crc32(data[summary_start : footer_at + 9 + 16])
    if calculated != saved:
        return f"summary CRC {calculated:#010x}, {saved:#010x} written (specification check)"
    return None


def verdict(path: str) -> str:
    with open(path, "rb") as f:
        data = f.read()
    try:
        with open(path, "rb") as f:
            for _ in StreamReader(f, skip_magic=False, validate_crcs=True).records:
                pass
    except Exception as e:  # the library's errors, struct errors of cut records, MemoryError …
        return f"refuse: {type(e).__name__}: {str(e)[:120]}"
    problem = summary_crc_problem(data)
    if problem:
        return f"refuse: {problem}"
    return "accept"


def main() -> None:
    for path in sys.argv[1:]:
        name = os.path.basename(path).removesuffix(".mcap")
        print(name, verdict(path))


if __name__ == "__main__":
    main()
