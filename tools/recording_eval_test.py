#!/usr/bin/env python3
"""Test of tools/recording_eval.py's annotated evaluation (run by ctest with /usr/bin/python3,
which has python3-rosbag): a bag written here with rosbag, in the format of
angusleigh/leg_tracker_benchmarks' annotations (leg_tracker/Person messages without a header,
each belonging to the latest scan before it), and a filtered scan's `_labels`.

Twenty scans at 10 Hz. The scanner drives for the first ten (the background, 5 m away, comes
0.1 m nearer in each scan) and stands from the tenth on (the same ranges). A person 2 m ahead
walks 0.1 m a scan away from the scanner until scan 10 and then stands. By the evaluator's rule
(the scanner stands; every annotation within 0.5 s either side within 0.15 m) the person stands
in scans 14-19: in scan 13 the annotation of scan 8, 0.2 m nearer, is within 0.5 s. The labels
remove the person's beams in scans 0-13 and keep them in 14-19, and remove one background beam
in every scan: the walking person's beams are all removed, the standing person's none."""
import math, os, sys, tempfile

import genpy.dynamic
import rosbag
import rospy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import recording_eval  # noqa: E402

PERSON_DEFINITION = """geometry_msgs/Pose pose
uint32 id

================================================================================
MSG: geometry_msgs/Pose
Point position
Quaternion orientation

================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z

================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
"""
SCAN_DEFINITION = """Header header
float32 angle_min
float32 angle_max
float32 angle_increment
float32 time_increment
float32 scan_time
float32 range_min
float32 range_max
float32[] ranges
float32[] intensities

================================================================================
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id
"""
# The message classes from their definitions (the bag stores them; sensor_msgs' Python module is
# not needed).
Person = genpy.dynamic.generate_dynamic('leg_tracker/Person', PERSON_DEFINITION)['leg_tracker/Person']
LaserScan = genpy.dynamic.generate_dynamic('sensor_msgs/LaserScan',
                                           SCAN_DEFINITION)['sensor_msgs/LaserScan']

BEAMS = 91  # One degree apart, -45 to 45 degrees.
PERSON_BEAMS = range(43, 48)  # -2 to 2 degrees: at 2 m, within 0.07 m of the annotation.

def person_x(k):
    return 2.0 + 0.1 * min(k, 10)

def write(path):
    with rosbag.Bag(path, 'w') as bag:
        for k in range(20):
            stamp = rospy.Time.from_sec(100.0 + 0.1 * k)
            scan = LaserScan()
            scan.header.stamp = stamp
            scan.angle_min = -math.radians(45.0)
            scan.angle_max = math.radians(45.0)
            scan.angle_increment = math.radians(1.0)
            scan.range_min, scan.range_max = 0.05, 20.0
            wall = 5.0 - 0.1 * min(k, 9)
            scan.ranges = [person_x(k) if b in PERSON_BEAMS else wall for b in range(BEAMS)]
            person_label = 1.0 if k <= 13 else 0.0
            scan.intensities = [person_label if b in PERSON_BEAMS else (1.0 if b == 0 else 0.0)
                                for b in range(BEAMS)]
            bag.write('/scan_labels', scan, stamp)
            person = Person()
            person.pose.position.x = person_x(k)
            person.id = 7
            bag.write('/people', person, stamp + rospy.Duration.from_sec(0.01))

def main():
    failures = []
    def expect(name, got, want):
        if got != want:
            failures.append('%s: %r, expected %r' % (name, got, want))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, 'annotated.bag')
        write(path)
        with rosbag.Bag(path) as bag:
            r = recording_eval.annotated(bag, '/scan', '/people', 0.4)
    expect('annotated_scans', r['annotated_scans'], 20)
    expect('annotated_scans_scanner_still', r['annotated_scans_scanner_still'], 10)
    expect('person_beams', r['person_beams'], 100)
    expect('walking_person_beams', r['walking_person_beams'], 70)
    expect('standing_person_beams', r['standing_person_beams'], 30)
    expect('walking_person_beams_removed', r['walking_person_beams_removed'], 1.0)
    expect('standing_person_beams_removed', r['standing_person_beams_removed'], 0.0)
    expect('person_beams_removed', r['person_beams_removed'], 0.7)
    expect('background_beams', r['background_beams'], 20 * (BEAMS - len(PERSON_BEAMS)))
    expect('background_kept', round(r['background_kept'], 6),
           round(1.0 - 20.0 / (20 * (BEAMS - len(PERSON_BEAMS))), 6))
    for f in failures:
        print('FAIL ' + f)
    print('%s: %s' % ('FAILED' if failures else 'OK', r))
    return 1 if failures else 0

if __name__ == '__main__':
    sys.exit(main())
