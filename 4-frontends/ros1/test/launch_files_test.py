#!/usr/bin/python3
"""The shipped launch files and parameter files, with roslaunch: dispel.launch starts both nodes
with config/default.yaml and the nodes' YAML files (parameters on the master under the names of
config/default.yaml), they subscribe and publish their topics, and the filter processes scans
(30 scans of the leg_tracker recording in, 30 out). A bad parameter makes a node exit at once,
with exit code 1 and a message naming it, whether it comes from a YAML file through roslaunch or
from the command line.
"""
import os
import subprocess
import time

from roslive import DRAIN_S, Failure, RosSession, check, env, read_topics, run

ROSLAUNCH = ["/usr/bin/python3", "/usr/bin/roslaunch"]
# Ten times the node's work per scan here (0.1 s waiting for a transform), five times the longest
# stall measured on a loaded machine (0.2 s, docs/ros1.md).
SETTLED_S = 1.0


def node_refuses(ros, name, args, expected):
    """Runs a node with bad parameters: it must exit 1 with the expected message."""
    p = ros.start(name, args)
    try:
        code = p.wait(30)
    except subprocess.TimeoutExpired:
        raise Failure("%s did not exit" % name)
    log = ros.log(name)
    print("%s: exit %d: %s" % (name, code, log.strip().splitlines()[-1] if log.strip() else ""))
    check(code == 1 and expected in log, "%s: expected exit 1 and '%s', got %d: %s" %
          (name, expected, code, log))


def main():
    source = env("SOURCE_DIR")
    work = os.path.join(env("WORK_DIR"), "launch")
    os.makedirs(work, exist_ok=True)
    leg_bag = os.path.join(source, "data/leg_tracker/demo_stationary_simple_environment.bag")
    out_bag = os.path.join(work, "launch.bag")
    if os.path.exists(out_bag):
        os.remove(out_bag)

    with RosSession(work) as ros:
        started = time.time()
        launch = ros.start("roslaunch", ROSLAUNCH + ["dispel", "dispel.launch"])
        ros.wait_for(lambda: ros.subscribed("/scan", "/dispel_filter") and
                     ros.subscribed("/wheels", "/dispel_odometry") and
                     ros.subscribed("/imu", "/dispel_odometry") and
                     ros.published("/scan_filtered", "/dispel_filter") and
                     ros.published("/odometry/filtered", "/dispel_odometry"), 60,
                     "the launch file did not bring both nodes up: " + ros.log("roslaunch"))
        print("dispel.launch: both nodes up in %.1f s" % (time.time() - started))
        params = {k: ros.master.getParam(k) for k in (
            "/dispel_filter/segmentation/cluster_gap_m", "/dispel_filter/fixed_frame",
            "/dispel_filter/classification/dynamic_weight_limit", "/dispel_odometry/odometry/model",
            "/dispel_odometry/wheel_message")}
        print("parameters: %s" % params)
        check(params == {"/dispel_filter/segmentation/cluster_gap_m": 0.1,
                         "/dispel_filter/fixed_frame": "odom",
                         "/dispel_filter/classification/dynamic_weight_limit": 8,
                         "/dispel_odometry/odometry/model": "ct",
                         "/dispel_odometry/wheel_message": "joint_state"}, "parameters differ")
        # Scans go through (unfiltered: nobody publishes odom -> laser here, and they are counted).
        topics = ["/scan_filtered", "/scan_labels"]
        recorder = ros.record("record", out_bag, topics)
        ros.wait_for(lambda: all((t, "/record") in ros.connections("/dispel_filter")
                                 for t in topics), 30,
                     "the filter node did not connect to the recorder")
        ros.play("play", leg_bag, ["-u", "3"], timeout=60, connected={"/scan": ["/dispel_filter"]})
        # The node waits transform_timeout_s (0.1 s) for each scan's pose, which never comes: all
        # scans are out when it has published nothing for SETTLED_S; then DRAIN_S for the
        # recorder to take what it received off its callback queue (roslive.DRAIN_S).
        ros.wait_delivered("/dispel_filter", "/record", topics, SETTLED_S, 60)
        time.sleep(DRAIN_S)
        ros.stop_recording(recorder, out_bag)
        out = read_topics(out_bag)
        n = len(out.get("/scan_filtered", []))
        print("3 s of scans through the launched filter: %d filtered, %d label scans" %
              (n, len(out.get("/scan_labels", []))))
        check(n >= 29 and len(out.get("/scan_labels", [])) == n, "scans did not go through")
        check(launch.poll() is None, "roslaunch ended: " + ros.log("roslaunch"))
        code = ros.stop(launch, 30)
        log = ros.log("roslaunch")
        check("process has died" not in log, "a node died: " + log)
        print("roslaunch stopped (exit %s)" % code)

        # A bad value in a YAML file, through the launch file.
        bad = os.path.join(work, "bad_filter.yaml")
        with open(bad, "w") as f:
            f.write("segmentation:\n  cluster_gap_m: -0.1\n")
        launch = ros.start("roslaunch_bad", ROSLAUNCH + ["dispel", "dispel_filter.launch",
                                                         "config:=" + bad])
        ros.wait_for(lambda: "process has died" in ros.log("roslaunch_bad"), 60,
                     "the filter node did not exit: " + ros.log("roslaunch_bad"))
        ros.stop(launch, 30)
        log = ros.log("roslaunch_bad")
        expected = ("bad parameter: parameters of /dispel_filter: segmentation.cluster_gap_m must "
                    "be a finite number > 0, got -0.1")
        check(expected in log and "exit code 1" in log, "expected '%s': %s" % (expected, log))
        print("dispel_filter.launch config:=bad_filter.yaml: the node exits 1: ...%s" % expected)

        launch = ros.start("roslaunch_bad_model", ROSLAUNCH + ["dispel", "dispel_odometry.launch",
                                                               "model:=cv"])
        ros.wait_for(lambda: "process has died" in ros.log("roslaunch_bad_model"), 60,
                     "the odometry node did not exit: " + ros.log("roslaunch_bad_model"))
        ros.stop(launch, 30)
        expected = "odometry.model must be one of ct, ct_euler, omni, got 'cv'"
        check(expected in ros.log("roslaunch_bad_model") and
              "exit code 1" in ros.log("roslaunch_bad_model"),
              "expected '%s': %s" % (expected, ros.log("roslaunch_bad_model")))
        print("dispel_odometry.launch model:=cv: the node exits 1: ...%s" % expected)

        # From the command line.
        filter_node, odometry_node = env("FILTER_NODE"), env("ODOMETRY_NODE")
        node_refuses(ros, "filter_policy", [filter_node, "__name:=f1",
                                            "_on_missing_transform:=maybe"],
                     "/f1/on_missing_transform must be one of drop, publish_unfiltered, "
                     "got 'maybe'")
        node_refuses(ros, "filter_unknown", [filter_node, "__name:=f2", "_fixed_frme:=odom"],
                     "parameters of /f2: unknown key 'fixed_frme'")
        node_refuses(ros, "filter_type", [filter_node, "__name:=f3",
                                          "_segmentation/min_points:=many"],
                     "segmentation.min_points must be an integer, got 'many'")
        node_refuses(ros, "odometry_unknown", [odometry_node, "__name:=o1", "_publish_tff:=true"],
                     "/o1/publish_tff is not a parameter of this node")
        node_refuses(ros, "odometry_window", [odometry_node, "__name:=o2",
                                              "_reorder_window_s:=-1"],
                     "/o2/reorder_window_s must be a finite number >= 0, got -1")
        node_refuses(ros, "odometry_timeout", [odometry_node, "__name:=o4",
                                               "_source_timeout_s:=0"],
                     "/o4/source_timeout_s must be a finite number > 0, got 0")
        node_refuses(ros, "odometry_track", [odometry_node, "__name:=o3",
                                             "_odometry/track_width_m:=0"],
                     "odometry.track_width_m must be")


if __name__ == "__main__":
    run(main)
