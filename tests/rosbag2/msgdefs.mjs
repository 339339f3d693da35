// ROS 2 (Humble/Jazzy) .msg definitions for the types write_mcap.mjs records, and
// the "ros2msg" complete-definition text that rosbag2 stores as the MCAP schema data.
//
// The field lists follow ROS 2 common_interfaces (std_msgs, geometry_msgs,
// sensor_msgs, nav_msgs, tf2_msgs, builtin_interfaces); comments are shortened.
// References to other types are spelled as in the real .msg files: with the
// package and no "/msg/" for other packages, bare for the same package.

export const MSG_TEXT = {
  "builtin_interfaces/msg/Time": `# This message communicates ROS Time defined here:
# https://design.ros2.org/articles/clock_and_time.html

# The seconds component, valid over all int32 values.
int32 sec

# The nanoseconds component, valid in the range [0, 10e9).
uint32 nanosec
`,
  "std_msgs/msg/Header": `# Standard metadata for higher-level stamped data types.
# This is generally used to communicate timestamped data
# in a particular coordinate frame.

# Two-integer timestamp that is expressed as seconds and nanoseconds.
builtin_interfaces/Time stamp

# Transform frame with which this data is associated.
string frame_id
`,
  "std_msgs/msg/String": `# This was originally provided as an example message.
# It is deprecated as of Foxy
# It is recommended to create your own semantically meaningful message.
# However if you would like to continue using this please use the equivalent in example_msgs.

string data
`,
  "geometry_msgs/msg/Point": `# This contains the position of a point in free space
float64 x
float64 y
float64 z
`,
  "geometry_msgs/msg/Vector3": `# This represents a vector in free space.

# This is semantically different than a point.
# A vector is always anchored at the origin.
# When a transform is applied to a vector, only the rotational component is applied.

float64 x
float64 y
float64 z
`,
  "geometry_msgs/msg/Quaternion": `# This represents an orientation in free space in quaternion form.

float64 x 0
float64 y 0
float64 z 0
float64 w 1
`,
  "geometry_msgs/msg/Pose": `# A representation of pose in free space, composed of position and orientation.

Point position
Quaternion orientation
`,
  "geometry_msgs/msg/PoseWithCovariance": `# This represents a pose in free space with uncertainty.

Pose pose

# Row-major representation of the 6x6 covariance matrix
# The orientation parameters use a fixed-axis representation.
# In order, the parameters are:
# (x, y, z, rotation about X axis, rotation about Y axis, rotation about Z axis)
float64[36] covariance
`,
  "geometry_msgs/msg/Twist": `# This expresses velocity in free space broken into its linear and angular parts.

Vector3  linear
Vector3  angular
`,
  "geometry_msgs/msg/TwistWithCovariance": `# This expresses velocity in free space with uncertainty.

Twist twist

# Row-major representation of the 6x6 covariance matrix
# The orientation parameters use a fixed-axis representation.
# In order, the parameters are:
# (x, y, z, rotation about X axis, rotation about Y axis, rotation about Z axis)
float64[36] covariance
`,
  "geometry_msgs/msg/Transform": `# This represents the transform between two coordinate frames in free space.

Vector3 translation
Quaternion rotation
`,
  "geometry_msgs/msg/TransformStamped": `# This expresses a transform from coordinate frame header.frame_id
# to the coordinate frame child_frame_id at the time of header.stamp
#
# This message is mostly used by the
# <a href="https://docs.ros.org/en/rolling/p/tf2/">tf2</a> package.
# See its documentation for more information.
#
# The child_frame_id is necessary in addition to the frame_id
# in the Header to communicate the full reference for the transform
# in a manner that's compatible with tf2.

# The frame id in the header is used as the reference frame of this transform.
std_msgs/Header header

# The frame id of the child frame to which this transform points.
string child_frame_id

# Translation and rotation in 3-dimensions of child_frame_id from header.frame_id.
Transform transform
`,
  "tf2_msgs/msg/TFMessage": `geometry_msgs/TransformStamped[] transforms
`,
  "nav_msgs/msg/Odometry": `# This represents an estimate of a position and velocity in free space.
# The pose in this message should be specified in the coordinate frame given by header.frame_id
# The twist in this message should be specified in the coordinate frame given by the child_frame_id

# Includes the frame id of the pose parent.
std_msgs/Header header

# Frame id the pose points to. The twist is in this coordinate frame.
string child_frame_id

# Estimated pose that is typically relative to a fixed world frame.
geometry_msgs/PoseWithCovariance pose

# Estimated linear and angular velocity relative to child_frame_id.
geometry_msgs/TwistWithCovariance twist
`,
  "sensor_msgs/msg/LaserScan": `# Single scan from a planar laser range-finder
#
# If you have another ranging device with different behavior (e.g. a sonar
# array), please find or create a different message, since applications
# will make fairly laser-specific assumptions about this data

std_msgs/Header header # timestamp in the header is the acquisition time of
                             # the first ray in the scan.
                             #
                             # in frame frame_id, angles are measured around
                             # the positive Z axis (counterclockwise, if Z is up)
                             # with zero angle being forward along the x axis

float32 angle_min            # start angle of the scan [rad]
float32 angle_max            # end angle of the scan [rad]
float32 angle_increment      # angular distance between measurements [rad]

float32 time_increment       # time between measurements [seconds] - if your scanner
                             # is moving, this will be used in interpolating position
                             # of 3d points
float32 scan_time            # time between scans [seconds]

float32 range_min            # minimum range value [m]
float32 range_max            # maximum range value [m]

float32[] ranges             # range data [m]
                             # (Note: values < range_min or > range_max should be discarded)
float32[] intensities        # intensity data [device-specific units].  If your
                             # device does not provide intensities, please leave
                             # the array empty.
`,
  "sensor_msgs/msg/Imu": `# This is a message to hold data from an IMU (Inertial Measurement Unit)
#
# Accelerations should be in m/s^2 (not in g's), and rotational velocity should be in rad/sec
#
# If the covariance of the measurement is known, it should be filled in (if all you know is the
# variance of each measurement, e.g. from the datasheet, just put those along the diagonal)
# A covariance matrix of all zeros will be interpreted as "covariance unknown", and to use the
# data a covariance will have to be assumed or gotten from some other source
#
# If you have no estimate for one of the data elements (e.g. your IMU doesn't produce an
# orientation estimate), please set element 0 of the associated covariance matrix to -1
# If you are interpreting this message, please check for a value of -1 in the first element of each
# covariance matrix, and disregard the associated estimate.

std_msgs/Header header

geometry_msgs/Quaternion orientation
float64[9] orientation_covariance # Row major about x, y, z axes

geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance # Row major about x, y, z axes

geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance # Row major x, y z
`,
  "sensor_msgs/msg/JointState": `# This is a message that holds data to describe the state of a set of torque controlled joints.
#
# The state of each joint (revolute or prismatic) is defined by:
#  * the position of the joint (rad or m),
#  * the velocity of the joint (rad/s or m/s) and
#  * the effort that is applied in the joint (Nm or N).
#
# Each joint is uniquely identified by its name
# The header specifies the time at which the joint states were recorded. All the joint states
# in one message have to be recorded at the same time.
#
# This message consists of a multiple arrays, one for each part of the joint state.
# The goal is to make each of the fields optional. When e.g. your joints have no
# effort associated with them, you can leave the effort array empty.
#
# All arrays in this message should have the same size, or be empty.
# This is the only way to uniquely associate the joint name with the correct
# states.

std_msgs/Header header

string[] name
float64[] position
float64[] velocity
float64[] effort
`,
};

// rosbag2's list of primitives (wstring is not in it).
const PRIMITIVES = new Set([
  "bool", "byte", "char", "float32", "float64", "int8", "uint8",
  "int16", "uint16", "int32", "uint32", "int64", "uint64", "string",
]);

/**
 * Dependencies of a .msg text the way rosbag2 finds them: the first word of each
 * non-comment line that is not a primitive type; a bare name gets the package
 * prefix ("Pose" in geometry_msgs -> "geometry_msgs/Pose"), a "pkg/Type" name is
 * kept as written (no "/msg/" inserted). Returned sorted (rosbag2 uses std::set).
 */
export function dependenciesOf(fullName) {
  const pkg = fullName.split("/")[0];
  const deps = new Set();
  for (const m of MSG_TEXT[fullName].matchAll(/(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+/g)) {
    const type = m[1];
    if (PRIMITIVES.has(type)) continue;
    deps.add(type.includes("/") ? type : `${pkg}/${type}`);
  }
  return [...deps].sort();
}

/** "pkg/Type" or "pkg/msg/Type" -> key of MSG_TEXT ("pkg/msg/Type"). */
function textKey(name) {
  const parts = name.split("/");
  const key = parts.length === 2 ? `${parts[0]}/msg/${parts[1]}` : name;
  if (!(key in MSG_TEXT)) throw new Error(`no definition for ${name}`);
  return key;
}

export const DELIMITER = "=".repeat(80);

/**
 * The complete definition as rosbag2's LocalMessageDefinitionSource builds it: the
 * root type's .msg text, then depth-first for each not-yet-seen dependency (sorted)
 * "\n" + 80 '=' + "\n" + "MSG: pkg/Type\n" + its text (which ends in "\n").
 */
export function ros2msgDefinition(fullName) {
  const seen = new Set();
  const build = (name) => {
    let out = MSG_TEXT[textKey(name)];
    for (const dep of dependenciesOf(textKey(name))) {
      if (seen.has(dep)) continue;
      seen.add(dep);
      out += `\n${DELIMITER}\nMSG: ${dep}\n` + build(dep);
    }
    return out;
  };
  return build(fullName);
}
