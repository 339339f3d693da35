#!/usr/bin/python3
"""dispel_odometry_node, live: robot_localization's Husky recording (test1.bag: wheel odometry as
nav_msgs/Odometry at 10 Hz, IMU at 30 Hz with the yaw rate on its y axis, 395 s) played with
rosbag play into two nodes at once, the CT model (publishing the TF odom -> base_link) and the
omnidirectional one, and their output recorded with rosbag record.

Checks: each node's trajectory equal to `dispel odom --model ct|omni` on the same recording
(same configuration: imu_yaw_axis y, track_width_m 0.555), estimate for estimate: as many
estimates as CSV rows, the same stamps, positions and yaw within 1e-6; the TF published once per
estimate by the node asked to.
"""
import csv
import math
import os
import subprocess
import time

from roslive import RosSession, check, diagnostic_values, env, read_topics, run

RATE = 10  # rosbag play -r: 400 messages/s.
# The IMU's stamps are 21 to 36 ms older than the wheels' when they arrive, and the two topics
# travel on separate connections. At -r 10 the node's default window, 0.1 s of stamp time, is
# 10 ms of wall time: enough in our runs, but a wheel message delayed more than that by a busy
# machine would be refused as out of order. (One early run lacked 18 wheel estimates, before the
# diagnostics were recorded and while rosbag play still read stray keys from a /dev/null that was
# a regular file; its cause is not known.) 1 s of stamp time is 100 ms of wall time here, what
# 0.1 s is when the robot runs in real time.
WINDOW_S = 1.0
WHEELS = "/husky_velocity_controller/odom"
IMU = "/imu/data"


def read_csv(path):
    with open(path) as f:
        return [(float(r["t"]), float(r["x"]), float(r["y"]), float(r["yaw"]))
                for r in csv.DictReader(f)]


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


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

    live_bag = os.path.join(work, "live.bag")
    for f in (live_bag, live_bag + ".active"):
        if os.path.exists(f):
            os.remove(f)
    with RosSession(work) as ros:
        nodes = {}
        for model in ("ct", "omni"):
            nodes[model] = ros.start("odometry_" + model, [
                env("ODOMETRY_NODE"), "__name:=dispel_odometry", "__ns:=/" + model,
                "wheels:=" + WHEELS, "imu:=" + IMU, "_wheel_message:=odometry",
                "_odometry/model:=" + model, "_odometry/imu_yaw_axis:=y",
                "_odometry/track_width_m:=0.555", "_publish_tf:=" + str(model == "ct").lower(),
                "_queue_size:=1000", "_reorder_window_s:=%g" % WINDOW_S,
                "_diagnostics_period_s:=0.5"])
        for model in nodes:
            ros.wait_for(lambda: ros.subscribed(WHEELS, "/%s/dispel_odometry" % model) and
                         ros.subscribed(IMU, "/%s/dispel_odometry" % model), 30,
                         "the %s node did not subscribe: %s" %
                         (model, ros.log("odometry_" + model)))
        recorder = ros.record("record_odometry", live_bag,
                              ["/ct/odometry/filtered", "/omni/odometry/filtered", "/tf",
                               "/diagnostics"])
        started = time.time()
        ros.play("play", bag, ["-r", str(RATE), "--queue", "1000", "--topics", WHEELS, IMU],
                 timeout=150)
        print("played %s at -r %d in %.1f s" % (os.path.basename(bag), RATE, time.time() - started))
        time.sleep(2.0)  # The last measurements wait for the reorder window, then are flushed.
        ros.stop_recording(recorder, live_bag)
        for model, node in nodes.items():
            check(node.poll() is None, "the %s node died: %s" % (model, ros.log("odometry_" + model)))
        live = read_topics(live_bag)

        for model in ("ct", "omni"):
            diag = [d for d in diagnostic_values(live.get("/diagnostics", []), ": odometry fusion")
                    if d.get("model") == model]
            check(diag, "no diagnostics from the %s node" % model)
            late = {k: int(v) for k, v in diag[-1].items() if "out of order" in k}
            print("%s: measurements refused as out of order: %s" % (model, late))
            msgs = sorted((m for m, _ in live.get("/%s/odometry/filtered" % model, [])),
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

        tf = [t for m, _ in live.get("/tf", []) for t in m.transforms
              if t.header.frame_id == "odom" and t.child_frame_id == "base_link"]
        n_ct = len(live.get("/ct/odometry/filtered", []))
        print("TF odom -> base_link: %d transforms for %d CT estimates" % (len(tf), n_ct))
        check(len(tf) == n_ct, "expected one transform per CT estimate (the omni node has none)")
        for model, node in nodes.items():
            check(ros.stop(node) == 0, "the %s node did not exit cleanly" % model)


if __name__ == "__main__":
    run(main)
