#!/usr/bin/env python3
"""sqlite3 (.db3) bags from the MCAP bag tools/tests/data/intel-bag, written with PyPI's rosbags
(not with anything of beamfield's), for `beamfield track --bag` tests:

- OUT/intel-bag-db3:   the same connections and messages (the same CDR bytes, the same
                       timestamps, in the same order), stored as ROS 2 Humble stores a
                       recording by default: a rosbag2 directory of metadata.yaml and a .db3.
- OUT/intel-bag-chain: the same, but the laser's mount is a chain of two /tf_static
                       transforms in two messages, as a nav2 robot publishes it:
                       base_footprint -> base_link (0.25, -0.10, 0.08 m, no rotation) and
                       base_link -> laser (-0.25, 0.10, 0.12 m, no rotation), which compose to
                       the single bag's base_link -> laser (the identity in the plane), plus an
                       unrelated base_link -> imu_link; and /tf carries the odometry as
                       odom -> base_footprint transforms (the /odom poses, at the /odom stamps)
                       beside the /odom topic.
- OUT/intel-bag-ld06:  the same as intel-bag-db3, but each scan is resampled as an LD06's ROS
                       driver publishes its revolutions: its own first angle and step, and its
                       own beam count (200 to 260 over the 180 degrees). A resampled beam at
                       angle a has the range of the original 1-degree beam nearest to a; no
                       beam lies within 0.005 deg of the half-way angle between two original
                       beams, so binning each scan back onto the original layout (nearest beam
                       within half a step) gives back the original ranges exactly. Seeded
                       (numpy default_rng(7)).

Usage: make_db3.py SRC_BAG OUT_DIR   (OUT_DIR must not hold the three bags yet)
"""

import math
import sys
from pathlib import Path

from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
import numpy as np  # rosbags depends on numpy

STORE = get_typestore(Stores.ROS2_JAZZY)
T = STORE.types
Header = T["std_msgs/msg/Header"]
Time = T["builtin_interfaces/msg/Time"]
Vector3 = T["geometry_msgs/msg/Vector3"]
Quaternion = T["geometry_msgs/msg/Quaternion"]
Transform = T["geometry_msgs/msg/Transform"]
TransformStamped = T["geometry_msgs/msg/TransformStamped"]
TFMessage = T["tf2_msgs/msg/TFMessage"]


def transform(stamp, parent, child, x, y, z, q):
    return TransformStamped(
        header=Header(stamp=stamp, frame_id=parent),
        child_frame_id=child,
        transform=Transform(translation=Vector3(x=x, y=y, z=z), rotation=q),
    )


def identity():
    return Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)


def resample(rng, scan):
    """The scan as an LD06 driver's revolution: see the module docs."""
    orig = np.asarray(scan.ranges, dtype=np.float32)
    a0 = float(np.float32(scan.angle_min))
    step0 = float(np.float32(scan.angle_increment))
    for _ in range(100000):
        n = int(rng.integers(200, 261))
        first = math.radians(-90.45 + float(rng.uniform(0.0, 0.3)))
        step = (math.radians(89.45) - first) / (n - 1)
        # The values the reader sees: f32 angles, bearings computed in f64 from them.
        first32, step32 = float(np.float32(first)), float(np.float32(step))
        k = (first32 + np.arange(n) * step32 - a0) / step0
        if np.all(np.abs(k - np.floor(k) - 0.5) > math.radians(0.005) / step0):
            j = np.floor(k + 0.5).astype(int)
            assert j.min() == 0 and j.max() == len(orig) - 1
            assert len(set(j.tolist())) == len(orig), "every original beam has a resampled one"
            ranges = orig[j]
            return scan.__class__(
                header=scan.header,
                angle_min=first32,
                angle_max=float(np.float32(first32 + (n - 1) * step32)),
                angle_increment=step32,
                time_increment=scan.time_increment,
                scan_time=scan.scan_time,
                range_min=scan.range_min,
                range_max=scan.range_max,
                ranges=ranges,
                intensities=np.array([], dtype=np.float32),
            )
    raise SystemExit("no resampling without a beam at a half-way angle")


def copy(src, dst, chain, ld06=False):
    rng = np.random.default_rng(7)
    with Reader(src) as r, Writer(dst, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
        conns = {}
        for c in r.connections:
            conns[c.id] = w.add_connection(c.topic, c.msgtype, typestore=STORE)
        tf = None
        if chain:
            tf = w.add_connection("/tf", TFMessage.__msgtype__, typestore=STORE)
        for c, t, raw in r.messages():
            if chain and c.topic == "/tf_static":
                msg = STORE.deserialize_cdr(raw, c.msgtype)
                stamp = msg.transforms[0].header.stamp
                # The child's transform first, in its own message: the reader must not rely
                # on the order of the chain.
                first = TFMessage(transforms=[
                    transform(stamp, "base_link", "laser", -0.25, 0.10, 0.12, identity()),
                    transform(stamp, "base_link", "imu_link", 0.05, 0.0, 0.2,
                              Quaternion(x=0.0, y=0.0, z=math.sin(0.3), w=math.cos(0.3))),
                ])
                second = TFMessage(transforms=[
                    transform(stamp, "base_footprint", "base_link", 0.25, -0.10, 0.08, identity()),
                ])
                w.write(conns[c.id], t, STORE.serialize_cdr(first, TFMessage.__msgtype__))
                w.write(conns[c.id], t + 1, STORE.serialize_cdr(second, TFMessage.__msgtype__))
                continue
            if ld06 and c.topic == "/scan":
                msg = resample(rng, STORE.deserialize_cdr(raw, c.msgtype))
                raw = STORE.serialize_cdr(msg, c.msgtype)
            w.write(conns[c.id], t, raw)
            if chain and c.topic == "/odom":
                odom = STORE.deserialize_cdr(raw, c.msgtype)
                p = odom.pose.pose
                msg = TFMessage(transforms=[transform(
                    odom.header.stamp, "odom", "base_footprint",
                    p.position.x, p.position.y, p.position.z, p.orientation)])
                w.write(tf, t, STORE.serialize_cdr(msg, TFMessage.__msgtype__))


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    src, out = Path(sys.argv[1]), Path(sys.argv[2])
    copy(src, out / "intel-bag-db3", chain=False)
    copy(src, out / "intel-bag-chain", chain=True)
    copy(src, out / "intel-bag-ld06", chain=False, ld06=True)
    print("wrote %s, %s and %s" % (out / "intel-bag-db3", out / "intel-bag-chain", out / "intel-bag-ld06"))


if __name__ == "__main__":
    main()
