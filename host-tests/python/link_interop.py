#!/usr/bin/env python3
"""An implementation of beamfield's device link written from docs/link-protocol.md alone:
COBS from the `cobs` package (PyPI), the CRC from Python's binascii.crc32, the layout with
struct. Run by host-tests/tests/link_protocol.rs; needs `pip install cobs==1.2.2`.

    link_interop.py decode FRAMES.bin
        Cuts the byte stream at each 0x00 and prints one line per non-empty frame:
        "<type> <seq> <field>..." (integers in decimal, f32 as "f:" and its 8 hex digits of
        bits, big-endian) or "error <kind>".
    link_interop.py encode LINES.txt OUT.bin
        Encodes every line (same format) as a frame; writes garbage, then the frames, then frames
        the receiver must refuse, and prints one "bad <kind> <type> <seq> <offset>" line per
        refused frame, in order.
"""

import binascii
import math
import struct
import sys

from cobs import cobs

VERSION = 2
MAX_POSITION_M = 1.0e5
# pi rounded to f32, as a double.
MAX_THETA_RAD = struct.unpack("<f", struct.pack("<f", math.pi))[0]
MAX_PARTICLES = 65535
MAX_ENCODED_LEN = 88

# type: (name, struct format of the payload). "f" fields are f32.
LAYOUT = {
    0x01: ("wheel_odometry", "<Qfff"),
    0x02: ("wheel_ticks", "<Qii"),
    0x03: ("set_initial_pose", "<Qfff9f"),
    0x04: ("start_global_localization", "<"),
    0x05: ("request_no_motion_update", "<"),
    0x06: ("set_parameters", "<BHfffff"),
    0x81: ("estimate", "<Qfff9ffHBffff"),
    0x82: ("heartbeat", "<Q12I"),
    0x83: ("error", "<BBHB"),
}


class Refused(Exception):
    def __init__(self, kind, offset=None):
        super().__init__(kind)
        self.kind = kind
        self.offset = offset


def f32_fields(fmt):
    """Indices (into the unpacked tuple) and payload offsets of the f32 fields of fmt."""
    out, index, offset = [], 0, 0
    for count, code in parse_format(fmt):
        for _ in range(count):
            if code == "f":
                out.append((index, offset))
            index += 1
            offset += struct.calcsize("<" + code)
    return out


def parse_format(fmt):
    items, count = [], ""
    for ch in fmt[1:]:
        if ch.isdigit():
            count += ch
        else:
            items.append((int(count or 1), ch))
            count = ""
    return items


def offsets(fmt):
    out, offset = [], 0
    for count, code in parse_format(fmt):
        for _ in range(count):
            out.append(offset)
            offset += struct.calcsize("<" + code)
    return out


def check_pose(v, at, x):
    """v[x], v[x+1], v[x+2] = x, y, theta; at = payload offsets."""
    for i in (x, x + 1):
        if not (math.isfinite(v[i]) and abs(v[i]) <= MAX_POSITION_M):
            raise Refused("out_of_range", at[i])
    if not (math.isfinite(v[x + 2]) and abs(v[x + 2]) <= MAX_THETA_RAD):
        raise Refused("out_of_range", at[x + 2])


def check_covariance(v, at, c):
    m = v[c : c + 9]
    for i in range(3):
        for j in range(3):
            k = 3 * i + j
            if not math.isfinite(m[k]):
                raise Refused("out_of_range", at[c + k])
            if i == j and m[k] < 0:
                raise Refused("out_of_range", at[c + k])
            if m[3 * j + i] != m[k]:
                raise Refused("out_of_range", at[c + k])


def check(t, v, fmt):
    """The valid ranges of docs/link-protocol.md; raises Refused with the field's offset."""
    at = offsets(fmt)
    if t == 0x01:
        check_pose(v, at, 1)
    elif t == 0x03:
        check_pose(v, at, 1)
        check_covariance(v, at, 4)
    elif t == 0x06:
        present = v[0]
        if present & 0xC0:
            raise Refused("out_of_range", 0)
        for bit, i in ((0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 6)):
            raw = struct.pack("<" + ("H" if i == 1 else "f"), v[i])
            if not present & (1 << bit) and raw != b"\0" * len(raw):
                raise Refused("out_of_range", at[i])
        if present & 1 and not 1 <= v[1] <= MAX_PARTICLES:
            raise Refused("out_of_range", at[1])
        if present & 2 and not (math.isfinite(v[2]) and v[2] > 0):
            raise Refused("out_of_range", at[2])
        for bit, i in ((2, 3), (3, 4), (4, 5), (5, 6)):
            if present & (1 << bit) and not (math.isfinite(v[i]) and v[i] >= 0):
                raise Refused("out_of_range", at[i])
    elif t == 0x81:
        if v[14] & ~0x3F:
            raise Refused("out_of_range", at[14])
        if v[15] > 3:
            raise Refused("out_of_range", at[15])
        check_pose(v, at, 1)
        check_covariance(v, at, 4)
        if not (math.isfinite(v[13]) and 0 <= v[13] <= MAX_PARTICLES):
            raise Refused("out_of_range", at[13])
        if not (math.isfinite(v[16]) and 0 <= v[16] <= 1):
            raise Refused("out_of_range", at[16])
        check_pose(v, at, 17)
    elif t == 0x83:
        if not 1 <= v[0] <= 7:
            raise Refused("out_of_range", 0)


def decode_frame(encoded):
    if len(encoded) > MAX_ENCODED_LEN:
        raise Refused("oversized")
    try:
        raw = cobs.decode(encoded)
    except cobs.DecodeError:
        raise Refused("bad_cobs")
    if len(raw) < 8:
        raise Refused("too_short")
    body, crc = raw[:-4], struct.unpack("<I", raw[-4:])[0]
    if binascii.crc32(body) != crc:
        raise Refused("bad_crc")
    version, t, seq = struct.unpack("<BBH", body[:4])
    if version != VERSION:
        raise Refused("wrong_version")
    if t not in LAYOUT:
        raise Refused("unknown_type")
    fmt = LAYOUT[t][1]
    payload = body[4:]
    if len(payload) != struct.calcsize(fmt):
        raise Refused("wrong_length")
    values = struct.unpack(fmt, payload)
    check(t, values, fmt)
    return t, seq, values


def token(value, is_f32):
    if is_f32:
        return "f:" + struct.pack(">f", value).hex()
    return str(value)


def line_of(t, seq, values):
    floats = {i for i, _ in f32_fields(LAYOUT[t][1])}
    fields = [token(v, i in floats) for i, v in enumerate(values)]
    return " ".join(["0x%02x" % t, str(seq)] + fields)


def values_of(t, tokens):
    out = []
    for tok in tokens:
        if tok.startswith("f:"):
            out.append(struct.unpack(">f", bytes.fromhex(tok[2:]))[0])
        else:
            out.append(int(tok))
    return out


def encode_frame(t, seq, payload, version=VERSION):
    body = struct.pack("<BBH", version, t, seq) + payload
    raw = body + struct.pack("<I", binascii.crc32(body))
    return cobs.encode(raw) + b"\0"


def decode_main(path):
    data = open(path, "rb").read()
    for encoded in data.split(b"\0")[:-1]:
        if not encoded:
            continue
        try:
            print(line_of(*decode_frame(encoded)))
        except Refused as e:
            print("error " + e.kind)


def encode_main(lines_path, out_path):
    out = bytearray()
    # Garbage without a delimiter, then one: the receiver loses that run only.
    out += bytes((i * 37 + 11) % 255 + 1 for i in range(40)) + b"\0"
    for line in open(lines_path):
        parts = line.split()
        if not parts:
            continue
        t, seq = int(parts[0], 16), int(parts[1])
        fmt = LAYOUT[t][1]
        values = values_of(t, parts[2:])
        check(t, values, fmt)  # never send what a receiver refuses
        out += encode_frame(t, seq, struct.pack(fmt, *values))

    def bad(kind, t, seq, offset, frame):
        out.extend(frame)
        print("bad %s 0x%02x %d %d" % (kind, t, seq, offset))

    nan = float("nan")
    cov = [0.25, 0.01, 0.0, 0.01, 0.16, 0.0, 0.0, 0.0, 0.07]
    pose = struct.pack("<Qfff", 5, 1.0, nan, 0.5)
    bad("out_of_range", 0x01, 900, 12, encode_frame(0x01, 900, pose))
    asym = cov[:]
    asym[1] = 0.02
    sip = struct.pack("<Qfff9f", 0, 1.0, 2.0, 3.0, *asym)
    bad("out_of_range", 0x03, 901, 24, encode_frame(0x03, 901, sip))
    far = struct.pack("<Qfff", 5, 1.0e6, 0.0, 0.0)
    bad("out_of_range", 0x01, 902, 8, encode_frame(0x01, 902, far))
    bad("wrong_version", 0x01, 903, 0, encode_frame(0x01, 903, pose, version=VERSION + 1))
    bad("unknown_type", 0x7E, 904, 0, encode_frame(0x7E, 904, b""))
    bad("wrong_length", 0x02, 905, 0, encode_frame(0x02, 905, b"\1" * 15))
    est = struct.pack("<Qfff9ffHBffff", 1, 0.0, 0.0, 0.0, *cov, 10.0, 0x40, 0, 0.0, 0.0, 0.0, 0.0)
    bad("out_of_range", 0x81, 906, 60, encode_frame(0x81, 906, est))
    params = struct.pack("<BHfffff", 0x02, 0, -1.0, 0.0, 0.0, 0.0, 0.0)
    bad("out_of_range", 0x06, 907, 3, encode_frame(0x06, 907, params))
    good = encode_frame(0x04, 908, b"")
    corrupt = bytearray(good)
    corrupt[-2] ^= 0x01  # a CRC byte
    bad("bad_crc", 0x04, 908, 0, bytes(corrupt))
    open(out_path, "wb").write(out)


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "decode":
        decode_main(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "encode":
        encode_main(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
