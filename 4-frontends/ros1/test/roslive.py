"""What the live ROS 1 tests share: a rosmaster of their own on a free port, processes started and
stopped by their process id (never by name), and reading the bags they record.

Run with /usr/bin/python3 (Debian's ROS modules are not on the other python3's path).
"""
import math
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client

import rosbag
import rosgraph

PLAY = "/usr/lib/rosbag/play"
RECORD = "/usr/lib/rosbag/record"
STATIC_TF = "/usr/lib/tf2_ros/static_transform_publisher"
# rosbag record drops what is still on its callback queue when it is stopped: once it has
# received everything (RosSession.received), a test gives it this long before stopping it. Its 10
# threads take a message off the queue in microseconds; a loaded machine stalled a process for up
# to 0.2 s (docs/ros1.md, the odometry node's measurements).
DRAIN_S = 1.0


def env(name):
    value = os.environ.get(name)
    if not value:
        sys.exit("%s is not set (the test is run by ctest)" % name)
    return value


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Failure(Exception):
    pass


def check(condition, message):
    if not condition:
        raise Failure(message)


class RosSession:
    """A rosmaster on a free port and the processes started through start(); close() stops each
    of them by its process id (SIGINT, then SIGTERM, then SIGKILL), newest first."""

    def __init__(self, work_dir):
        self.work_dir = work_dir
        os.makedirs(work_dir, exist_ok=True)
        self.port = free_port()
        self.env = dict(os.environ)
        self.env.update({
            "ROS_MASTER_URI": "http://127.0.0.1:%d" % self.port,
            "ROS_IP": "127.0.0.1",
            "ROS_HOSTNAME": "127.0.0.1",
            "ROSCONSOLE_STDOUT_LINE_BUFFERED": "1",
            "PYTHONUNBUFFERED": "1",
            "ROS_HOME": os.path.join(work_dir, "ros_home"),
            "ROS_LOG_DIR": os.path.join(work_dir, "ros_log"),
        })
        devel = os.environ.get("ROS_DEVEL")
        if devel:  # The package in the build tree, catkin layout, for roslaunch.
            self.env["ROS_PACKAGE_PATH"] = os.path.join(devel, "share") + ":/usr/share"
            self.env["CMAKE_PREFIX_PATH"] = devel
        os.environ.update({k: self.env[k] for k in ("ROS_MASTER_URI", "ROS_IP")})
        self.processes = []  # (name, Popen, log path)
        self.start("rosmaster", ["/usr/bin/python3", "/usr/bin/rosmaster", "--core", "-p",
                                 str(self.port), "-w", "3"])
        self.master = rosgraph.Master("/dispel_live_test", master_uri=self.env["ROS_MASTER_URI"])
        self.wait_for(self._master_up, 20, "rosmaster did not come up")
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))

    def _master_up(self):
        try:
            self.master.getPid()
            return True
        except Exception:
            return False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def start(self, name, command):
        log_path = os.path.join(self.work_dir, name + ".log")
        log = open(log_path, "w")
        # Standard input is a pipe that stays empty, not /dev/null: rosbag play reads keys from
        # it (space pauses, 's' steps, '+' and '-' change the rate), and where /dev/null is a
        # regular file holding what others wrote to it (as on the machine these tests were
        # written on) it reads them. SIGINT back to its default: a shell's background job
        # ignores it, and so would the children, yet rosbag record must have it to close its bag.
        p = subprocess.Popen(command, env=self.env, stdout=log, stderr=subprocess.STDOUT,
                             stdin=subprocess.PIPE, cwd=self.work_dir,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        self.processes.append((name, p, log_path))
        return p

    def log(self, name):
        for n, _, path in self.processes:
            if n == name:
                with open(path) as f:
                    return f.read()
        return ""

    def stop(self, p, timeout=15):
        """Stops one process we started, by its pid; returns its exit code."""
        if p.stdin:
            p.stdin.close()
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
            try:
                return p.wait(timeout)
            except subprocess.TimeoutExpired:
                p.terminate()
                try:
                    return p.wait(5)
                except subprocess.TimeoutExpired:
                    p.kill()
        return p.wait()

    def close(self):
        for _, p, _ in reversed(self.processes):
            self.stop(p)
        self.processes = []

    def wait_for(self, condition, timeout, message, period=0.1):
        end = time.time() + timeout
        while time.time() < end:
            if condition():
                return
            time.sleep(period)
        raise Failure(message)

    def state(self):
        publishers, subscribers, _ = self.master.getSystemState()
        return dict(publishers), dict(subscribers)

    def subscribed(self, topic, node=None):
        _, subs = self.state()
        nodes = subs.get(topic, [])
        return bool(nodes) if node is None else any(n.startswith(node) for n in nodes)

    def published(self, topic, node=None):
        pubs, _ = self.state()
        nodes = pubs.get(topic, [])
        return bool(nodes) if node is None else any(n.startswith(node) for n in nodes)

    def connections(self, node):
        """The (topic, peer node) pairs of the connections a node has made, by its getBusInfo."""
        try:
            uri = self.master.lookupNode(node)
            _, _, info = xmlrpc.client.ServerProxy(uri).getBusInfo("/dispel_live_test")
        except Exception:
            return set()
        return {(c[4], c[1]) for c in info if c[5]}

    def _bus_stats(self, node):
        """[publications, subscriptions] of a roscpp node's getBusStats (which, unlike the other
        calls, answers without a status code and message)."""
        try:
            uri = self.master.lookupNode(node)
            return xmlrpc.client.ServerProxy(uri).getBusStats("/dispel_live_test")[:2]
        except Exception:
            return [[], []]

    def sent(self, node, topic):
        """Messages a (roscpp) node has sent on a topic, over all its connections."""
        return sum(c[3] for t, conns in self._bus_stats(node)[0] if t == topic for c in conns)

    def received(self, node, topic):
        """Messages a (roscpp) node has received on a topic, over all its connections."""
        return sum(c[2] for t, conns in self._bus_stats(node)[1] if t == topic for c in conns)

    def wait_delivered(self, publisher, subscriber, topics, settled_s, timeout):
        """Waits until the subscriber has received every message the publisher sent on each topic
        and the publisher has sent nothing more for settled_s."""
        last, since = None, time.time()
        end = time.time() + timeout
        while time.time() < end:
            sent = [self.sent(publisher, t) for t in topics]
            if sent != last:
                last, since = sent, time.time()
            elif (time.time() - since >= settled_s and
                  sent == [self.received(subscriber, t) for t in topics]):
                return sent
            time.sleep(0.1)
        raise Failure("%s did not receive what %s sent on %s in %d s" %
                      (subscriber, publisher, topics, timeout))

    def record(self, name, output, topics):
        """Starts rosbag record and waits until it subscribes to every topic."""
        p = self.start(name, [RECORD, "-O", output, "--tcpnodelay", "__name:=" + name] + topics)
        self.wait_for(lambda: all(self.subscribed(t, "/" + name) for t in topics), 30,
                      "rosbag record did not subscribe to %s" % topics)
        return p

    def play(self, name, bag, args, timeout, connected=None):
        """Plays a bag with rosbag play and waits for it to end. With connected ({topic: [node]}),
        the player starts paused and is let go (a space on its standard input) only when it has a
        connection to each of those nodes on each topic: --wait-for-subscribers waits for the
        first subscriber of a topic only, and a second one still connecting would miss the first
        messages (how long a connection takes depends on the machine's load)."""
        if connected:
            p = self.start(name, [PLAY, "-q", "--pause", bag, "__name:=" + name] + args)
            wanted = {(t, n) for t, nodes in connected.items() for n in nodes}
            self.wait_for(lambda: p.poll() is not None or
                          wanted <= self.connections("/" + name), 30,
                          "rosbag play did not connect to %s: it has %s" %
                          (sorted(wanted), sorted(self.connections("/" + name))))
            p.stdin.write(b" ")
            p.stdin.flush()
        else:
            p = self.start(name, [PLAY, "-q", "--wait-for-subscribers", "-d", "0.5", bag] + args)
        try:
            code = p.wait(timeout)
        except subprocess.TimeoutExpired:
            raise Failure("rosbag play did not finish in %d s" % timeout)
        check(code == 0, "rosbag play failed (%s): %s" % (code, self.log(name)))

    def stop_recording(self, p, output):
        code = self.stop(p, 30)
        check(os.path.exists(output), "rosbag record wrote no %s (exit %s)" % (output, code))


class Listener:
    """Subscribes from the test's own process (rospy) and keeps every message of the topics, as
    rosbag record would, but can be asked what it has received: a test waits until the messages
    it expects are there instead of sleeping for a guessed time before stopping a recorder. One
    per process (rospy has one node per process), on the master of the session it is given."""

    def __init__(self, session, topics):
        import rospy
        os.environ.update({k: session.env[k] for k in ("ROS_HOME", "ROS_LOG_DIR")})
        rospy.init_node("dispel_live_test", anonymous=True, disable_signals=True)
        self.rospy = rospy
        self.lock = threading.Lock()
        self.raw = {t: [] for t in topics}
        self.classes = {}
        # AnyMsg: kept serialised while the test runs, decoded when asked for with the message
        # definition its publisher sent (as rosbag does: Debian packages no Python module for
        # nav_msgs or diagnostic_msgs).
        self.subscribers = {t: rospy.Subscriber(t, rospy.AnyMsg, self._received, callback_args=t,
                                                tcp_nodelay=True) for t in topics}

    def _received(self, msg, topic):
        with self.lock:
            self.raw[topic].append((msg._buff, msg._connection_header))

    def connected(self, topic, publishers=1):
        return self.subscribers[topic].get_num_connections() >= publishers

    def count(self, topic):
        with self.lock:
            return len(self.raw[topic])

    def messages(self, topic):
        """The messages received on a topic so far, decoded, in the order received."""
        import genpy.dynamic
        with self.lock:
            raw = list(self.raw[topic])
        out = []
        for buff, header in raw:
            name = header["type"]
            if name not in self.classes:
                self.classes[name] = genpy.dynamic.generate_dynamic(
                    name, header["message_definition"])[name]
            out.append(self.classes[name]().deserialize(buff))
        return out

    def close(self):
        for s in self.subscribers.values():
            s.unregister()
        self.rospy.signal_shutdown("the test is done")


def read_topics(path, topics=None):
    """{topic: [(message, receive time)]} of a bag."""
    out = {}
    with rosbag.Bag(path) as bag:
        for topic, msg, t in bag.read_messages(topics=topics):
            out.setdefault(topic, []).append((msg, t))
    return out


def stamp_key(msg):
    return msg.header.stamp.to_nsec()


def same_ranges(a, b):
    """Equal range arrays, NaN equal to NaN."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if x != y and not (math.isnan(x) and math.isnan(y)):
            return False
    return True


def diagnostic_values(messages, status_suffix):
    """The key-value dictionaries of every /diagnostics status whose name ends with the suffix."""
    out = []
    for msg, _ in messages:
        for status in msg.status:
            if status.name.endswith(status_suffix):
                out.append({kv.key: kv.value for kv in status.values})
    return out


def run(main, timeout_s=240):
    """Runs a test's main(); exit code 0 when it passes, 1 with the reason when it does not. After
    timeout_s the test fails (and its sessions stop what they started) rather than hang."""
    started = time.time()

    def expired(*_):
        raise Failure("timed out after %d s" % timeout_s)

    signal.signal(signal.SIGALRM, expired)
    signal.alarm(timeout_s)
    try:
        main()
    except Failure as e:
        print("FAILED: %s" % e, flush=True)
        sys.exit(1)
    print("passed in %.1f s" % (time.time() - started), flush=True)
