#!/usr/bin/env python3
"""A ROS 2 bag (MCAP) from a CARMEN laser log, written with PyPI's rosbags (not with anything of
beamfield's), for trying `beamfield track --bag` on a recording that looks like a robot's:

- /scan       sensor_msgs/LaserScan: each FLASER line's ranges (counter-clockwise from -90 deg
              in 1 deg steps for a 180-beam line), stamped with the line's timestamp;
- /odom       nav_msgs/Odometry: wheel odometry made from the logged poses with the errors of a
              real robot: a distance scale of 1.02, a heading drift of 0.5 deg per metre driven and
              of 1 % of every turn (the log's own odometry fields repeat its corrected poses);
- /ground_truth geometry_msgs/PoseWithCovarianceStamped: the logged (corrected) pose;
- /tf_static  tf2_msgs/TFMessage: base_link -> laser, the identity (the log's poses are the
              laser's).

Usage: carmen_to_bag.py LOG OUT_DIR [--first N] [--count N]
OUT_DIR is a rosbag2 directory (metadata.yaml and one .mcap file), as `ros2 bag record` makes.
"""

import argparse
import math
import sys

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

STORE = get_typestore(Stores.ROS2_JAZZY)
T = STORE.types
Time = T["builtin_interfaces/msg/Time"]
Header = T["std_msgs/msg/Header"]
LaserScan = T["sensor_msgs/msg/LaserScan"]
Odometry = T["nav_msgs/msg/Odometry"]
Pose = T["geometry_msgs/msg/Pose"]
Point = T["geometry_msgs/msg/Point"]
Quaternion = T["geometry_msgs/msg/Quaternion"]
PoseWithCovariance = T["geometry_msgs/msg/PoseWithCovariance"]
PoseWithCovarianceStamped = T["geometry_msgs/msg/PoseWithCovarianceStamped"]
Twist = T["geometry_msgs/msg/Twist"]
TwistWithCovariance = T["geometry_msgs/msg/TwistWithCovariance"]
Vector3 = T["geometry_msgs/msg/Vector3"]
Transform = T["geometry_msgs/msg/Transform"]
TransformStamped = T["geometry_msgs/msg/TransformStamped"]
TFMessage = T["tf2_msgs/msg/TFMessage"]

import numpy as np  # noqa: E402  (rosbags depends on numpy)


def stamp(t):
    sec = int(math.floor(t))
    return Time(sec=sec, nanosec=int(round((t - sec) * 1e9)) % 1_000_000_000)


def quat(yaw):
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def read_flaser(path):
    for line in open(path):
        f = line.split()
        if not f or f[0] != "FLASER":
            continue
        n = int(f[1])
        ranges = [float(v) for v in f[2:2 + n]]
        x, y, th = (float(v) for v in f[2 + n:5 + n])
        t = float(f[8 + n])
        yield t, ranges, (x, y, th)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log")
    ap.add_argument("out")
    ap.add_argument("--first", type=int, default=0, help="first FLASER line used")
    ap.add_argument("--count", type=int, default=None, help="FLASER lines used")
    args = ap.parse_args()

    scans = list(read_flaser(args.log))[args.first:]
    if args.count is not None:
        scans = scans[: args.count]
    if len(scans) < 2:
        sys.exit("fewer than two FLASER lines")
    t0 = scans[0][0]
    base = 1_700_000_000.0  # stamps as a recording's: seconds since the Unix epoch
    zero_cov = [0.0] * 36
    with Writer(args.out, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        c_scan = w.add_connection("/scan", LaserScan.__msgtype__, typestore=STORE)
        c_odom = w.add_connection("/odom", Odometry.__msgtype__, typestore=STORE)
        c_truth = w.add_connection("/ground_truth", PoseWithCovarianceStamped.__msgtype__, typestore=STORE)
        c_tf = w.add_connection("/tf_static", TFMessage.__msgtype__, typestore=STORE)

        def write(conn, t, msg):
            w.write(conn, int(round(t * 1e9)), STORE.serialize_cdr(msg, msg.__msgtype__))

        tf = TFMessage(transforms=[TransformStamped(
            header=Header(stamp=stamp(base), frame_id="base_link"),
            child_frame_id="laser",
            transform=Transform(translation=Vector3(x=0.0, y=0.0, z=0.0), rotation=quat(0.0)),
        )])
        write(c_tf, base, tf)
        odom = list(scans[0][2])
        prev = scans[0][2]
        for t, ranges, pose in scans:
            ts = base + (t - t0)
            # Odometry: the logged motion in the robot's frame, with systematic errors.
            dx, dy = pose[0] - prev[0], pose[1] - prev[1]
            c, s = math.cos(prev[2]), math.sin(prev[2])
            fwd, side = c * dx + s * dy, -s * dx + c * dy
            turn = wrap(pose[2] - prev[2])
            dist = math.hypot(fwd, side)
            fwd, side = 1.02 * fwd, 1.02 * side
            turn = 1.01 * turn + math.radians(0.5) * dist
            co, so = math.cos(odom[2]), math.sin(odom[2])
            odom = [odom[0] + co * fwd - so * side, odom[1] + so * fwd + co * side, wrap(odom[2] + turn)]
            prev = pose
            n = len(ranges)
            scan = LaserScan(
                header=Header(stamp=stamp(ts), frame_id="laser"),
                angle_min=-math.pi / 2,
                angle_max=-math.pi / 2 + math.radians(n - 1),
                angle_increment=math.radians(1.0),
                time_increment=0.0,
                scan_time=0.0,
                range_min=0.0,
                range_max=81.83,
                ranges=np.array(ranges, dtype=np.float32),
                intensities=np.array([], dtype=np.float32),
            )
            write(c_scan, ts, scan)
            write(c_odom, ts, Odometry(
                header=Header(stamp=stamp(ts), frame_id="odom"),
                child_frame_id="base_link",
                pose=PoseWithCovariance(pose=Pose(position=Point(x=odom[0], y=odom[1], z=0.0), orientation=quat(odom[2])),
                                        covariance=np.array(zero_cov)),
                twist=TwistWithCovariance(twist=Twist(linear=Vector3(x=0.0, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.0)),
                                          covariance=np.array(zero_cov)),
            ))
            write(c_truth, ts, PoseWithCovarianceStamped(
                header=Header(stamp=stamp(ts), frame_id="map"),
                pose=PoseWithCovariance(pose=Pose(position=Point(x=pose[0], y=pose[1], z=0.0), orientation=quat(pose[2])),
                                        covariance=np.array(zero_cov)),
            ))
    print("%d scans from %s into %s" % (len(scans), args.log, args.out))


if __name__ == "__main__":
    main()
