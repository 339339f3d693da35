#!/usr/bin/python3
"""dispel_odometry_node, live: robot_localization's Husky recording (test1.bag: wheel odometry as
nav_msgs/Odometry at 10 Hz, IMU at 30 Hz with the yaw rate on its y axis, 395 s) played with
rosbag play into two nodes at once, the CT model (publishing the TF odom -> base_link) and the
omnidirectional one, and their output received by the test itself (roslive.Listener).

Checks: no measurement late (refused); each node's trajectory equal to `dispel odom --model
ct|omni` on the same recording (same configuration: imu_yaw_axis y, track_width_m 0.555),
estimate for estimate: as many estimates as CSV rows, the same stamps, positions and yaw within
1e-6 (the CSV prints 9 significant digits); the TF published once per estimate by the node asked
to.

Why no measurement may be late, on any machine: the node fuses a measurement once both topics
have delivered a later stamp (pipeline::OdometryRunner), and each topic arrives in order on its
own connection (one publisher; the test checks that each topic's stamps increase in the
recording). How far apart the two connections deliver does not matter: on a loaded machine the
wheels arrived up to 1.68 s of stamp time behind the IMU (at -r 10; docs/ros1.md), more than any
window measured from the newest stamp could have covered without delaying every estimate. What
could still make one late: a topic silent for source_timeout_s of wall time while the other
delivers (the node then stops waiting for it). The longest gap the nodes measured in 15 runs
under load was 0.22 s (docs/ros1.md): the default, 0.5 s, is what a robot should wait for a
failed sensor; the test takes SOURCE_TIMEOUT_S, about ten times that gap, as here it only
decides how long the end of the recording waits. reorder_window_s is the default (0.05 s).

Time limits, none of which the result depends on: the player starts only once it is connected to
both nodes on both topics (roslive.RosSession.play); the test then waits until both nodes
report every measurement of the recording received, none waiting, and it has every estimate they
report published, at most END_S (about 2.5 s is expected: source_timeout_s, then a
diagnostics period). The estimates are published with a queue of 1000 (queue_size), 2.5 s here: the test's
subscriber would have to stall 12 times longer than the longest stall measured to lose one.
"""
import csv
import math
import os
import subprocess
import time

import rosbag

from roslive import Listener, RosSession, check, diagnostic_values, env, run

RATE = 10  # rosbag play -r: 400 messages/s, the recording in 40 s.
END_S = 60  # How long to wait for the last estimates before failing.
WHEELS = "/husky_velocity_controller/odom"
IMU = "/imu/data"
NODES = {"ct": "/ct/dispel_odometry", "omni": "/omni/dispel_odometry"}
SOURCE_TIMEOUT_S = 2.0  # Wall time; see above.


def read_csv(path):
    with open(path) as f:
        return [(float(r["t"]), float(r["x"]), float(r["y"]), float(r["yaw"]))
                for r in csv.DictReader(f)]


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def recording_counts(bag):
    """Messages per input topic, each topic's stamps checked to increase in the recording."""
    counts, last = {WHEELS: 0, IMU: 0}, {}
    with rosbag.Bag(bag) as b:
        for topic, msg, _ in b.read_messages(topics=[WHEELS, IMU]):
            t = msg.header.stamp.to_nsec()
            check(t >= last.get(topic, 0), "%s: stamps go back in the recording" % topic)
            last[topic] = t
            counts[topic] += 1
    return counts


def latest_diagnostics(listener, model):
    diag = [d for d in diagnostic_values([(m, None) for m in listener.messages("/diagnostics")],
                                         ": odometry fusion") if d.get("model") == model]
    return diag[-1] if diag else None


def main():
    source = env("SOURCE_DIR")
    work = os.path.join(env("WORK_DIR"), "odometry")
    bag = os.path.join(source, "data/robot_localization/test1.bag")
    os.makedirs(work, exist_ok=True)
    config = os.path.join(work, "husky.yaml")
    with open(config, "w") as f:
        f.write("odometry: {imu_yaw_axis: y, track_width_m: 0.555}\n")
    offline = {}
    for model in ("ct", "omni"):
        out = os.path.join(work, model + ".csv")
        subprocess.run([env("DISPEL"), "odom", bag, "-o", out, "--model", model, "--config",
                        config], check=True, stdout=subprocess.DEVNULL, timeout=120)
        offline[model] = read_csv(out)
    counts = recording_counts(bag)

    with RosSession(work) as ros:
        nodes = {}
        for model in ("ct", "omni"):
            nodes[model] = ros.start("odometry_" + model, [
                env("ODOMETRY_NODE"), "__name:=dispel_odometry", "__ns:=/" + model,
                "wheels:=" + WHEELS, "imu:=" + IMU, "_wheel_message:=odometry",
                "_odometry/model:=" + model, "_odometry/imu_yaw_axis:=y",
                "_odometry/track_width_m:=0.555", "_publish_tf:=" + str(model == "ct").lower(),
                "_queue_size:=1000", "_source_timeout_s:=%g" % SOURCE_TIMEOUT_S,
                "_diagnostics_period_s:=0.5"])
        for model, name in NODES.items():
            ros.wait_for(lambda: ros.subscribed(WHEELS, name) and ros.subscribed(IMU, name), 30,
                         "the %s node did not subscribe: %s" %
                         (model, ros.log("odometry_" + model)))
        listener = Listener(ros, ["/ct/odometry/filtered", "/omni/odometry/filtered", "/tf",
                                  "/diagnostics"])
        ros.wait_for(lambda: listener.connected("/ct/odometry/filtered") and
                     listener.connected("/omni/odometry/filtered") and
                     listener.connected("/tf") and listener.connected("/diagnostics", 2), 30,
                     "the test did not connect to the nodes' outputs")
        started = time.time()
        ros.play("play", bag, ["-r", str(RATE), "--queue", "1000", "--topics", WHEELS, IMU],
                 timeout=150, connected={WHEELS: NODES.values(), IMU: NODES.values()})
        print("played %s at -r %d in %.1f s" % (os.path.basename(bag), RATE, time.time() - started))

        def finished(model):
            d = latest_diagnostics(listener, model)
            return (d is not None and int(d["wheels received"]) == counts[WHEELS] and
                    int(d["imu received"]) == counts[IMU] and
                    int(d["waiting for reordering"]) == 0 and
                    listener.count("/%s/odometry/filtered" % model) ==
                    int(d["estimates published"]) and
                    (model != "ct" or ros.sent(NODES["ct"], "/tf") == int(d["estimates published"])))

        ended = time.time()
        ros.wait_for(lambda: all(finished(m) for m in NODES), END_S,
                     "the nodes did not report every measurement fused and published in %d s: %s"
                     % (END_S, {m: latest_diagnostics(listener, m) for m in NODES}))
        print("last estimates in %.1f s after the player ended" % (time.time() - ended))
        for model, node in nodes.items():
            check(node.poll() is None, "the %s node died: %s" % (model, ros.log("odometry_" + model)))

        for model in ("ct", "omni"):
            d = latest_diagnostics(listener, model)
            print("%s: late %s wheel, %s IMU; arrived out of order within their topic %s, %s; "
                  "largest lag behind the newest stamp %s s (wheels), %s s (IMU); longest gap "
                  "(wall) %s s, %s s; given up as quiet %s, %s times (the end of the recording: "
                  "once each)" %
                  (model, d["wheels late"], d["imu late"], d["wheels arrived out of order"],
                   d["imu arrived out of order"], d["wheels largest lag behind newest (s)"],
                   d["imu largest lag behind newest (s)"], d["wheels longest gap (s)"],
                   d["imu longest gap (s)"], d["wheels given up as quiet"],
                   d["imu given up as quiet"]))
            check(int(d["wheels late"]) == 0 and int(d["imu late"]) == 0,
                  "%s: measurements refused as late (see the docstring): %s" % (model, d))
            msgs = sorted(listener.messages("/%s/odometry/filtered" % model),
                          key=lambda m: m.header.stamp.to_nsec())
            rows = offline[model]
            print("%s: %d estimates from the node, %d rows from dispel odom" %
                  (model, len(msgs), len(rows)))
            check(len(msgs) == len(rows), "%s: %d estimates, dispel odom wrote %d rows" %
                  (model, len(msgs), len(rows)))
            dt = dpos = dyaw = 0.0
            for m, (t, x, y, yaw) in zip(msgs, rows):
                check(m.header.frame_id == "odom" and m.child_frame_id == "base_link",
                      "frames %s -> %s" % (m.header.frame_id, m.child_frame_id))
                p = m.pose.pose.position
                dt = max(dt, abs(m.header.stamp.to_sec() - t))
                dpos = max(dpos, math.hypot(p.x - x, p.y - y))
                dyaw = max(dyaw, abs(math.remainder(yaw_of(m.pose.pose.orientation) - yaw,
                                                    2 * math.pi)))
            end = msgs[-1].pose.pose.position
            print("%s: largest differences to dispel odom: stamp %.2g s, position %.2g m, yaw "
                  "%.2g rad; end at (%.2f, %.2f) m after %.0f s" %
                  (model, dt, dpos, dyaw, end.x, end.y, rows[-1][0] - rows[0][0]))
            check(dt < 1e-6 and dpos < 1e-6 and dyaw < 1e-6,
                  "%s: the node's trajectory differs from dispel odom's" % model)

        # One transform per CT estimate sent (the omni node sends none). tf2_ros broadcasts with a
        # queue of 100, a quarter of a second here: a subscriber stalled longer loses some, by
        # design, so those received are checked, not counted.
        n_ct = listener.count("/ct/odometry/filtered")
        tf = [t for m in listener.messages("/tf") for t in m.transforms]
        print("TF: %d transforms sent for %d CT estimates, %d received" %
              (ros.sent(NODES["ct"], "/tf"), n_ct, len(tf)))
        check(ros.sent(NODES["ct"], "/tf") == n_ct and ros.sent(NODES["omni"], "/tf") == 0,
              "expected one transform per CT estimate (the omni node has none)")
        check(0 < len(tf) <= n_ct and all(t.header.frame_id == "odom" and
                                          t.child_frame_id == "base_link" for t in tf),
              "transforms other than odom -> base_link")
        listener.close()
        for model, node in nodes.items():
            check(ros.stop(node) == 0, "the %s node did not exit cleanly" % model)


if __name__ == "__main__":
    run(main)
