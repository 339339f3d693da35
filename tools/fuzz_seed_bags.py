#!/usr/bin/env python3
"""Writes the small ROS 1 bags of the bag fuzz target's seed corpus (tests/fuzz/corpus/ros1_bag/):
one message of each kind dispel decodes (LaserScan, Odometry, TFMessage, JointState, Imu,
NavSatFix) and a message of another type, in bags without compression, with bz2 and with lz4, and
one bag with a scan of the shipped leg_tracker recording. Written with the real ROS bag library
(Debian's python3-rosbag), the messages serialised by hand (Debian ships no Python message
classes); a few kB each.

  /usr/bin/python3 tools/fuzz_seed_bags.py tests/fuzz/corpus/ros1_bag
"""
import os
import struct
import sys

import rosbag
import rospy

MD5 = {
    'sensor_msgs/LaserScan': '90c7ef2dc6895d81024acba2ac42f369',
    'sensor_msgs/JointState': '3066dcd76a6cfaef579bd0f34173e9fd',
    'sensor_msgs/Imu': '6a62c6daae103f4ff57a132d6f95cec2',
    'sensor_msgs/NavSatFix': '2d3a8cd499b9b4a0249fb98fd05cfa48',
    'nav_msgs/Odometry': 'cd5e73d190d741a2f92e81eda573aca7',
    'tf2_msgs/TFMessage': '94810edda583a504dfda3829e70d7eec',
    'std_msgs/String': '992ce8a1687cec8c8bd883ec73ca41d1',
}


def string(s):
    b = s.encode()
    return struct.pack('<I', len(b)) + b


def header(seq, sec, frame):
    return struct.pack('<III', seq, sec, 500000000) + string(frame)


def doubles(*v):
    return struct.pack('<%dd' % len(v), *v)


def array(fmt, values):
    return struct.pack('<I', len(values)) + b''.join(struct.pack('<' + fmt, v) for v in values)


def messages():
    scan = (header(1, 100, 'laser') + struct.pack('<7f', -1.5, 1.5, 0.5, 0.0, 0.1, 0.1, 10.0) +
            array('f', [1.0, 2.0, float('nan'), 3.0, 11.0, 0.05, 2.5]) + array('f', [1.0] * 7))
    odom = (header(2, 100, 'odom') + string('base_link') + doubles(1, 2, 0, 0, 0, 0.38, 0.92) +
            doubles(*[0.0] * 36) + doubles(0.5, 0, 0, 0, 0, 0.1) + doubles(*[0.0] * 36))
    transform = header(3, 100, 'base_link') + string('laser') + doubles(0.2, 0, 0, 0, 0, 0, 1)
    tf = struct.pack('<I', 2) + transform + transform
    joints = (header(4, 100, '') + struct.pack('<I', 2) + string('left_wheel_joint') +
              string('right_wheel_joint') + array('d', [0.0, 0.0]) + array('d', [0.4, 0.6]) +
              array('d', []))
    imu = (header(5, 100, 'imu') + doubles(0, 0, 0, 1) + doubles(-1, *[0.0] * 8) +
           doubles(0, 0, 0.1) + doubles(*[0.0] * 9) + doubles(0, 0, 9.8) + doubles(*[0.0] * 9))
    fix = (header(6, 100, 'gps') + struct.pack('<bH', 0, 1) + doubles(57.7, 11.9, 20) +
           doubles(*[0.0] * 9) + struct.pack('<B', 0))
    return [('/scan', 'sensor_msgs/LaserScan', scan), ('/odom', 'nav_msgs/Odometry', odom),
            ('/tf_static', 'tf2_msgs/TFMessage', tf),
            ('/joint_states', 'sensor_msgs/JointState', joints),
            ('/imu/data', 'sensor_msgs/Imu', imu), ('/fix', 'sensor_msgs/NavSatFix', fix),
            ('/note', 'std_msgs/String', string('hello'))]


class Type:
    """What rosbag's raw write needs of a message class."""

    def __init__(self, name):
        self._type = name
        self._md5sum = MD5[name]
        self._full_text = ''


def write(path, compression, msgs):
    with rosbag.Bag(path, 'w', compression=compression) as bag:
        for i, (topic, kind, data) in enumerate(msgs):
            t = rospy.Time(100, 10000000 * (i + 1))
            bag.write(topic, (kind, data, MD5[kind], Type(kind)), t, raw=True)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for compression in ('none', 'bz2', 'lz4'):
        write(os.path.join(out, 'kinds_%s.bag' % compression), compression, messages())
    here = os.path.dirname(os.path.abspath(__file__))
    shipped = os.path.join(here, '..', 'data', 'leg_tracker',
                           'demo_stationary_simple_environment.bag')
    with rosbag.Bag(shipped) as bag:
        for _, raw, _ in bag.read_messages(topics=['/scan'], raw=True):
            scan = raw[1]
            break
    write(os.path.join(out, 'leg_tracker_scan.bag'), 'lz4',
          [('/scan', 'sensor_msgs/LaserScan', scan)] + messages()[1:3])


if __name__ == '__main__':
    main()
