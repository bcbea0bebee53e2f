# A minimal TIFF writer for the tests: one float32 grey channel, uncompressed, one strip (TIFF 6.0, Adobe 1992).
# Written here rather than through fvm so that reading it checks fvm's reader against an independent writer.
import struct

import numpy as np


def write_float_tiff(path, heights):
    heights = np.ascontiguousarray(heights, dtype="<f4")
    rows, cols = heights.shape
    pixels = heights.tobytes()
    entries = [  # tag, type (3 SHORT, 4 LONG), value; sorted by tag as the format requires
        (256, 4, cols), (257, 4, rows), (258, 3, 32), (259, 3, 1), (262, 3, 1), (273, 4, 0),
        (277, 3, 1), (278, 4, rows), (279, 4, len(pixels)), (284, 3, 1), (339, 3, 3),
    ]
    ifd_offset = 8
    data_offset = ifd_offset + 2 + 12 * len(entries) + 4
    ifd = struct.pack("<H", len(entries))
    for tag, kind, value in entries:
        if tag == 273:
            value = data_offset
        ifd += struct.pack("<HHI", tag, kind, 1) + (struct.pack("<HH", value, 0) if kind == 3 else struct.pack("<I", value))
    ifd += struct.pack("<I", 0)
    with open(path, "wb") as f:
        f.write(b"II*\x00" + struct.pack("<I", ifd_offset) + ifd + pixels)
