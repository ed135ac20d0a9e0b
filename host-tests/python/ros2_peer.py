#!/usr/bin/env python3
"""A ROS 2 peer for `beamfield bridge`, written with PyPI's cyclonedds (Eclipse Cyclone DDS and
its Python IDL layer), not with anything of beamfield's: the ROS 2 message types are declared
here from their .msg definitions, with ROS 2's DDS names (topic `rt/<name>`, type
`<pkg>::msg::dds_::<Type>_`; services `rq/<name>Request` / `rr/<name>Reply` with rmw_cyclonedds'
request header).

It prints the poses it receives on amcl_pose and the transforms on /tf, then:
1. publishes an `initialpose` 0.8 m beside the latest estimate and checks that the device's next
   estimates start there (the round trip: ROS 2 -> bridge -> link -> device -> link -> bridge ->
   ROS 2);
2. publishes an `initialpose` with a NaN position, which the bridge must refuse (counted) while
   it keeps running;
3. calls the `request_nomotion_update` service and waits for the reply.

Exit status 0 when every check passed, 1 otherwise; one line per check.

Traffic stays on 127.0.0.1: run it with CYCLONEDDS_URI as `loopback_uri()` gives (the
default when the variable is unset).
"""

import argparse
import math
import os
import sys
import time
from dataclasses import dataclass

LOOPBACK = (
    "<CycloneDDS><Domain><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers>"
    "</Discovery></Domain></CycloneDDS>"
)
os.environ.setdefault("CYCLONEDDS_URI", LOOPBACK)

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.idl.types import array, float64, int32, int64, sequence, uint8, uint32, uint64  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose
    covariance: array[float64, 36]


@dataclass
class PoseWithCovarianceStamped(
    IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovarianceStamped_"
):
    header: Header
    pose: PoseWithCovariance


@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion


@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform


@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped]


# rmw_cyclonedds puts a request header (the client's GUID prefix as a u64 and a sequence
# number) before every request and reply.
@dataclass
class EmptyRequest(IdlStruct, typename="std_srvs::srv::dds_::Empty_Request_"):
    client_guid: uint64
    sequence_number: int64
    structure_needs_at_least_one_member: uint8


@dataclass
class EmptyResponse(IdlStruct, typename="std_srvs::srv::dds_::Empty_Response_"):
    client_guid: uint64
    sequence_number: int64
    structure_needs_at_least_one_member: uint8


def yaw_of(q):
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def stamp_ns(t):
    return t.sec * 1_000_000_000 + t.nanosec


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--domain", type=int, default=0)
    ap.add_argument("--kidnap-after", type=int, default=3,
                    help="poses before the initialpose (the Intel replay turns in place for its first 12)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds for the whole run")
    ap.add_argument("--tolerance", type=float, default=1.0, help="the bridge's transform_tolerance, s")
    ap.add_argument("--verbose", action="store_true", help="print every pose and transform")
    args = ap.parse_args()

    dp = DomainParticipant(args.domain)
    latched = Qos(
        Policy.Reliability.Reliable(duration(seconds=1)),
        Policy.Durability.TransientLocal,
        Policy.History.KeepLast(1),
    )
    reliable = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.History.KeepLast(100))
    poses = DataReader(dp, Topic(dp, "rt/amcl_pose", PoseWithCovarianceStamped, qos=latched), qos=latched)
    tf = DataReader(dp, Topic(dp, "rt/tf", TFMessage, qos=reliable), qos=reliable)
    initialpose = DataWriter(dp, Topic(dp, "rt/initialpose", PoseWithCovarianceStamped, qos=reliable), qos=reliable)
    rq = DataWriter(dp, Topic(dp, "rq/request_nomotion_updateRequest", EmptyRequest, qos=reliable), qos=reliable)
    rr = DataReader(dp, Topic(dp, "rr/request_nomotion_updateReply", EmptyResponse, qos=reliable), qos=reliable)

    checks = []

    def check(name, ok, detail):
        checks.append(ok)
        print("%s %s: %s" % ("ok" if ok else "FAILED", name, detail), flush=True)

    got, transforms, last = 0, 0, None
    tf_pairs = 0  # transforms whose stamp is a pose's stamp + transform_tolerance
    pose_stamps = set()
    commanded, commanded_at, before = None, None, None
    after = []
    nan_sent, nan_at = False, None
    request_sent_at, reply = None, None
    end = time.time() + args.timeout
    while time.time() < end:
        for s in poses.take(50):
            if not isinstance(s, PoseWithCovarianceStamped):
                continue  # an instance-state notification, no data
            got += 1
            p = s.pose.pose
            last = (p.position.x, p.position.y, yaw_of(p.orientation))
            pose_stamps.add(stamp_ns(s.header.stamp))
            if args.verbose or got <= 3 or got % 100 == 0:
                print(
                    "amcl_pose %d: stamp %d.%09d frame %s x %.3f y %.3f yaw %.3f var_x %.5f"
                    % (got, s.header.stamp.sec, s.header.stamp.nanosec, s.header.frame_id,
                       last[0], last[1], last[2], s.pose.covariance[0]),
                    flush=True,
                )
            if commanded is not None and len(after) < 8:
                after.append(last)
        for m in tf.take(50):
            if not isinstance(m, TFMessage):
                continue
            for t in m.transforms:
                transforms += 1
                if args.verbose or transforms <= 3:
                    print(
                        "tf %s -> %s: stamp %d.%09d x %.3f y %.3f yaw %.3f"
                        % (t.header.frame_id, t.child_frame_id, t.header.stamp.sec,
                           t.header.stamp.nanosec, t.transform.translation.x,
                           t.transform.translation.y, yaw_of(t.transform.rotation)),
                        flush=True,
                    )
                if stamp_ns(t.header.stamp) - round(args.tolerance * 1e9) in pose_stamps:
                    tf_pairs += 1
        if commanded is None and got >= args.kidnap_after and last is not None:
            before = last
            commanded = (last[0] + 0.8, last[1], last[2])
            cov = [0.0] * 36
            cov[0] = cov[7] = 0.0025
            cov[35] = 0.0025
            q = Quaternion(0.0, 0.0, math.sin(commanded[2] / 2), math.cos(commanded[2] / 2))
            initialpose.write(PoseWithCovarianceStamped(
                Header(Time(0, 0), "map"),
                PoseWithCovariance(Pose(Point(commanded[0], commanded[1], 0.0), q), cov)))
            commanded_at = got
            print("initialpose sent: x %.3f y %.3f yaw %.3f (0.8 m beside the estimate)" % commanded, flush=True)
        if commanded is not None and len(after) >= 8 and not nan_sent:
            nan_sent, nan_at = True, got
            q = Quaternion(0.0, 0.0, 0.0, 1.0)
            initialpose.write(PoseWithCovarianceStamped(
                Header(Time(0, 0), "map"),
                PoseWithCovariance(Pose(Point(float("nan"), 1.0, 0.0), q), [0.0] * 36)))
            print("initialpose with a NaN position sent", flush=True)
            rq.write(EmptyRequest(0x0102030405060708, 1, 0))
            request_sent_at = time.time()
            print("request_nomotion_update called", flush=True)
        if request_sent_at is not None and reply is None:
            for r in rr.take(10):
                if isinstance(r, EmptyResponse) and r.client_guid == 0x0102030405060708 and r.sequence_number == 1:
                    reply = time.time() - request_sent_at
            if reply is None and time.time() - request_sent_at > 10:
                break
        if reply is not None and nan_at is not None and got >= nan_at + 10:
            break
        time.sleep(0.01)

    check("poses", got > args.kidnap_after, "%d amcl_pose messages received" % got)
    check("tf", transforms > 0 and tf_pairs > 0,
          "%d map -> odom transforms, %d stamped a pose's stamp + %.1f s" % (transforms, tf_pairs, args.tolerance))
    if commanded is None or not after:
        check("initialpose", False, "no estimate came back after the initialpose")
    else:
        # The first estimate may still come from a scan the device had before the command.
        d = [math.hypot(a[0] - commanded[0], a[1] - commanded[1]) for a in after]
        moved = min(d)
        check("initialpose", moved < 0.4 and math.hypot(before[0] - commanded[0], before[1] - commanded[1]) > 0.7,
              "estimate before %.3f m from the commanded pose; the next %d estimates %s m from it"
              % (math.hypot(before[0] - commanded[0], before[1] - commanded[1]), len(d),
                 ", ".join("%.3f" % v for v in d)))
    check("service", reply is not None,
          "request_nomotion_update answered after %.3f s" % reply if reply is not None else "no reply")
    check("still running", nan_at is not None and got >= nan_at + 10,
          "%d poses after the NaN initialpose" % (got - nan_at if nan_at is not None else 0))
    return 0 if all(checks) else 1


if __name__ == "__main__":
    sys.exit(main())
