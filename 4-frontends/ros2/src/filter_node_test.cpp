// The ROS 2 filter node's work without DDS: its parameter file, the sensor pose from /tf and
// /tf_static, scans waiting for it, and what happens when it never comes.
#include "dispel/ros2/filter_node.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "dispel/io/errors.hpp"
#include "dispel/io/ros2_messages.hpp"
#include "test_files.hpp"

namespace dispel::ros2 {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string parse_error(const std::string& yaml, const std::string& node = "dispel_filter") {
  try {
    parse_filter_node_parameters(yaml, "p.yaml", node);
  } catch (const io::ConfigError& e) {
    return e.what();
  }
  return "parsed";
}

TEST(Ros2FilterNodeParameters, Ros2sLayoutFlatFilesAndTheFiltersKeys) {
  const std::string ros2 =
      "dispel_filter:\n"
      "  ros__parameters:\n"
      "    fixed_frame: /map\n"
      "    scan_topic: front/scan\n"
      "    on_missing_transform: drop\n"
      "    queue_size: 4\n"
      "    scale_to_scanner: true\n"
      "    max_time_gap_s: 2.5\n"
      "    tracking: {match_distance_m: 0.3}\n"
      "other_node:\n"
      "  ros__parameters: {fixed_frame: x}\n";
  const FilterNodeSettings s = parse_filter_node_parameters(ros2, "p.yaml", "dispel_filter");
  EXPECT_EQ(s.fixed_frame, "map");
  EXPECT_EQ(s.scan_topic, "/front/scan");
  EXPECT_TRUE(s.drop_without_transform);
  EXPECT_EQ(s.queue_size, 4);
  EXPECT_TRUE(s.runner.scale_to_scanner);
  EXPECT_EQ(s.runner.config.max_time_gap_s, 2.5);
  EXPECT_EQ(s.runner.config.tracking.match_distance_m, 0.3);
  // "/**" is every node's; a flat file is the node's; nothing is the defaults.
  EXPECT_EQ(parse_filter_node_parameters("/**:\n  ros__parameters: {fixed_frame: map}\n", "p",
                                         "dispel_filter")
                .fixed_frame,
            "map");
  EXPECT_EQ(parse_filter_node_parameters("static_sensor: true\n", "p", "n").static_sensor, true);
  EXPECT_EQ(parse_filter_node_parameters("", "p", "n").fixed_frame, "odom");

  EXPECT_EQ(parse_error("other:\n  ros__parameters: {}\n"),
            "p.yaml: has parameters for 'other', not for 'dispel_filter' or /**");
  EXPECT_EQ(parse_error("queue_size: 0\n"),
            "p.yaml: queue_size must be an integer from 1 to 1000000 (got '0')");
  EXPECT_EQ(parse_error("queue_size: 2.5\n"),
            "p.yaml: queue_size must be an integer from 1 to 1000000 (got '2.5')");
  EXPECT_EQ(parse_error("on_missing_transform: wait\n"),
            "p.yaml: on_missing_transform must be publish_unfiltered or drop (got 'wait')");
  EXPECT_EQ(parse_error("transform_timeout_s: .nan\n"),
            "p.yaml: transform_timeout_s must be a finite number >= 0 (got '.nan')");
  EXPECT_TRUE(parse_filter_node_parameters("use_sim_time: true\n", "p", "n").use_sim_time);
  EXPECT_NE(parse_error("no_such_key: 1\n").find("no_such_key"), std::string::npos);
  EXPECT_EQ(parse_error("- a list\n"), "p.yaml: must be a mapping of parameters");
  EXPECT_NE(parse_error("a: [\n").find("p.yaml: not YAML"), std::string::npos);
}

// Several files, as ros2 launch passes them (a parameter file, then its own with use_sim_time),
// each with "/**" and the node's block: merged in order, a later value replacing an earlier one.
// A typo that makes a node's block a string is an error that names the file, not an abort.
TEST(Ros2FilterNodeParameters, SeveralFilesAndBlocksMergeAsRos2sDo) {
  const FilterNodeSettings s = parse_filter_node_parameters(
      {{"/**:\n  ros__parameters: {fixed_frame: map, queue_size: 3}\n"
        "dispel_filter:\n  ros__parameters: {queue_size: 5, static_sensor: true}\n",
        "a.yaml"},
       {"/**:\n  ros__parameters: {use_sim_time: true}\n", "b.yaml"},
       {"/**:\n  ros__parameters: {queue_size: 7}\n", "-p queue_size:=7"}},
      "dispel_filter");
  EXPECT_EQ(s.fixed_frame, "map");
  EXPECT_TRUE(s.static_sensor);
  EXPECT_TRUE(s.use_sim_time);
  EXPECT_EQ(s.queue_size, 7);
  // (Read as a flat file, whose key the filter does not know.)
  EXPECT_EQ(parse_error("dispel_filter: ros__parameters\n"), "p.yaml: unknown key 'dispel_filter'");
}

// Without scans, the robot's motion is kept for 10 s (tf2's buffer), not for as long as the
// node runs.
TEST(Ros2FilterNodeCore, TheMotionKeptIsBoundedWithoutScans) {
  FilterNodeCore core(FilterNodeSettings{});
  for (int k = 0; k < 100000; ++k) {
    io::TransformsMessage m;
    m.transforms.push_back(
        {io::Stamp::from_seconds(1000.0 + 0.01 * k), "odom", "base_link", Pose2{}});
    core.transforms(m, false);
  }
  EXPECT_LE(core.motion_kept(), 1002u);
}

// The shipped parameter file states the defaults.
TEST(Ros2FilterNodeParameters, TheShippedParameterFileStatesTheDefaults) {
  const std::string path = test::source_path("4-frontends/ros2/config/dispel_filter.yaml");
  const FilterNodeSettings s =
      parse_filter_node_parameters(test::read_bytes(path), path, "dispel_filter");
  const FilterNodeSettings d;
  EXPECT_EQ(s.scan_topic, d.scan_topic);
  EXPECT_EQ(s.fixed_frame, d.fixed_frame);
  EXPECT_EQ(s.static_sensor, d.static_sensor);
  EXPECT_EQ(s.transform_timeout_s, d.transform_timeout_s);
  EXPECT_EQ(s.drop_without_transform, d.drop_without_transform);
  EXPECT_EQ(s.queue_size, d.queue_size);
  EXPECT_EQ(s.runner.scale_to_scanner, d.runner.scale_to_scanner);
  EXPECT_EQ(s.runner.scan_period_s, d.runner.scan_period_s);
  EXPECT_EQ(s.ros_distro, d.ros_distro);
  EXPECT_EQ(s.use_sim_time, d.use_sim_time);
  EXPECT_EQ(parse_error("ros_distro: noetic\n"),
            "p.yaml: ros_distro 'noetic' is not humble, iron, jazzy, kilted or rolling");
}

// A laser 0.2 m ahead of base_link in a 6 m round room, 360 beams.
io::ScanMessage room_scan(double t) {
  io::ScanMessage m;
  m.header.stamp = io::Stamp::from_seconds(t);
  m.header.frame_id = "laser";
  m.scan.stamp_s = m.header.stamp.seconds();
  m.scan.angle_min_rad = -kPi;
  m.scan.angle_increment_rad = 2 * kPi / 360;
  m.angle_max = static_cast<float>(kPi - 2 * kPi / 360);
  m.scan.range_min_m = 0.1F;
  m.scan.range_max_m = 20.0F;
  m.scan.ranges_m.assign(360, 6.0F);
  return m;
}

io::TransformsMessage transform(double t, const std::string& parent, const std::string& child,
                                Pose2 pose) {
  io::TransformsMessage m;
  m.transforms.push_back({io::Stamp::from_seconds(t), parent, child, pose});
  return m;
}

TEST(Ros2FilterNodeCore, AScanWaitsForItsPoseFromTfAndItsMountFromTfStatic) {
  FilterNodeSettings s;
  s.transform_timeout_s = 0.5;
  FilterNodeCore core(s);
  core.transforms(transform(0.0, "base_link", "laser", {0.2, 0.0, 0.0}), true);
  core.transforms(transform(99.9, "odom", "base_link", {1.0, 0.0, 0.0}), false);
  // The scan at t = 100 is after the last pose (99.9, beyond the tolerance): it waits.
  EXPECT_TRUE(core.scan(room_scan(100.0), 1000.0, 0.0).empty());
  EXPECT_TRUE(core.poll(1000.1).empty());
  core.transforms(transform(100.1, "/odom", "/base_link", {2.0, 0.0, 0.0}), false);
  const std::vector<FilterNodeOutput> out = core.poll(1000.2);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].outcome, pipeline::ScanOutcome::kFiltered);
  EXPECT_EQ(out[0].filtered.header.frame_id, "laser");
  EXPECT_EQ(out[0].labels.scan.intensities.size(), 360u);
  EXPECT_EQ(core.counts().published, 1);
}

TEST(Ros2FilterNodeCore, WithoutAPoseInTimeAScanIsPublishedUnfilteredOrDropped) {
  for (const bool drop : {false, true}) {
    FilterNodeSettings s;
    s.transform_timeout_s = 0.1;
    s.drop_without_transform = drop;
    FilterNodeCore core(s);
    EXPECT_TRUE(core.scan(room_scan(5.0), 10.0, 0.0).empty());
    EXPECT_TRUE(core.poll(10.05).empty());
    const std::vector<FilterNodeOutput> out = core.poll(10.11);
    if (drop) {
      EXPECT_TRUE(out.empty());
      EXPECT_EQ(core.counts().dropped_without_transform, 1);
    } else {
      ASSERT_EQ(out.size(), 1u);
      // Without a pose the filter registers the scan itself (the default configuration), so it
      // is filtered; all of the room is kept.
      EXPECT_EQ(out[0].outcome, pipeline::ScanOutcome::kFiltered);
      EXPECT_EQ(out[0].filtered.scan.ranges_m, room_scan(5.0).scan.ranges_m);
    }
  }
}

// /diagnostics: the filter's status as the ROS 1 node says it, WARN in a period with scans without
// a sensor pose (published unfiltered or dropped), and what this node counts besides.
TEST(Ros2FilterNodeCore, DiagnosticsWarnOfScansWithoutAPoseInTheirPeriod) {
  FilterNodeSettings s;
  s.node_name = "front_filter";
  s.transform_timeout_s = 0.1;
  s.drop_without_transform = true;
  FilterNodeCore core(s);
  const auto value = [](const pipeline::DiagnosticStatus& d, const std::string& key) {
    for (const auto& [k, v] : d.values) {
      if (k == key) return v;
    }
    return std::string("(missing)");
  };
  EXPECT_TRUE(core.scan(room_scan(5.0), 10.0, 0.0).empty());
  EXPECT_TRUE(core.poll(10.2).empty());  // Dropped: no pose within 0.1 s.
  core.count_undecodable();
  pipeline::DiagnosticStatus d = core.diagnostics(2);
  EXPECT_EQ(d.name, "front_filter: dynamic filter");
  EXPECT_EQ(d.level, pipeline::DiagnosticStatus::Level::kWarn);
  EXPECT_NE(d.message.find("1 without a sensor pose"), std::string::npos) << d.message;
  EXPECT_EQ(value(d, "scans"), "1");
  EXPECT_EQ(value(d, "scans without a sensor pose"), "1");
  EXPECT_EQ(value(d, "scans dropped (no sensor pose)"), "1");
  EXPECT_EQ(value(d, "undecodable messages"), "3");
  EXPECT_EQ(value(d, "scans dropped (queue full)"), "0");
  EXPECT_EQ(value(d, "scans received"), "1");
  EXPECT_EQ(value(d, "scans waiting for a sensor pose"), "0");
  // The next period has none: OK again, the totals kept.
  d = core.diagnostics(2);
  EXPECT_EQ(d.level, pipeline::DiagnosticStatus::Level::kOk);
  EXPECT_EQ(value(d, "scans without a sensor pose"), "1");
}

// A scan before the first pose will never have one: it goes at once. The queue is bounded: the
// oldest waiting scans are dropped and counted.
TEST(Ros2FilterNodeCore, ScansThatCanNeverHaveAPoseGoAtOnceAndTheQueueIsBounded) {
  FilterNodeSettings s;
  s.transform_timeout_s = 10.0;
  s.queue_size = 3;
  FilterNodeCore core(s);
  core.transforms(transform(0.0, "base_link", "laser", {}), true);
  core.transforms(transform(50.0, "odom", "base_link", {}), false);
  const std::vector<FilterNodeOutput> early = core.scan(room_scan(40.0), 1.0, 0.0);
  ASSERT_EQ(early.size(), 1u);
  for (int k = 0; k < 5; ++k) EXPECT_TRUE(core.scan(room_scan(60.0 + k), 2.0, 0.0).empty());
  EXPECT_EQ(core.counts().dropped_queue_full, 2);
  core.transforms(transform(70.0, "odom", "base_link", {}), false);
  EXPECT_EQ(core.poll(2.1).size(), 3u);  // 62, 63, 64: interpolated.
  EXPECT_EQ(core.counts().scans_in, 6);
  EXPECT_EQ(core.counts().published, 4);
  // A transform that is not finite, or not after the last one, is refused and counted.
  core.transforms(transform(69.0, "odom", "base_link", {}), false);
  core.transforms(transform(71.0, "base_link", "laser", {std::nan(""), 0.0, 0.0}), true);
  EXPECT_EQ(core.counts().transforms_refused, 2);
}

// A recording played again (ros2 bag play --loop, /clock reset): the transforms from the fixed
// frame jump back. The motion of the earlier run is forgotten, so the new run's poses are taken
// (a PoseBuffer refuses what is not after its last pose); a transform a little out of order is
// refused, not taken for a new run.
TEST(Ros2FilterNodeCore, TimeGoingBackwardsStartsTheMotionAfresh) {
  FilterNodeCore core(FilterNodeSettings{});
  core.transforms(transform(0.0, "base_link", "laser", {}), true);
  for (int k = 0; k <= 10; ++k)
    core.transforms(transform(100.0 + k, "odom", "base_link", {}), false);
  core.transforms(transform(109.5, "odom", "base_link", {}), false);  // Out of order.
  EXPECT_EQ(core.counts().transforms_refused, 1);
  EXPECT_EQ(core.counts().time_resets, 0);
  core.transforms(transform(100.0, "odom", "base_link", {1.0, 0.0, 0.0}), false);
  core.transforms(transform(101.0, "odom", "base_link", {2.0, 0.0, 0.0}), false);
  EXPECT_EQ(core.counts().time_resets, 1);
  EXPECT_EQ(core.counts().transforms_refused, 1);  // The new run's are taken.
  const std::vector<FilterNodeOutput> out = core.scan(room_scan(100.5), 0.0, 0.0);
  ASSERT_EQ(out.size(), 1u);  // Its pose is the new run's.
  EXPECT_EQ(out[0].outcome, pipeline::ScanOutcome::kFiltered);
}

// A driver without a clock leaves the stamp zero: the scan is filtered at the ROS time it came
// (the system's, or /clock's), and published with its own header.
TEST(Ros2FilterNodeCore, AScanWithoutAStampIsFilteredAtTheTimeItCame) {
  FilterNodeSettings s;
  s.static_sensor = true;
  FilterNodeCore core(s);
  io::ScanMessage zero = room_scan(0.0);
  const std::vector<FilterNodeOutput> out = core.scan(zero, 5.0, 1700000000.5);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].filtered.scan.stamp_s, 1700000000.5);
  EXPECT_TRUE(out[0].filtered.header.stamp.is_zero());
  EXPECT_EQ(core.counts().zero_stamps, 1);
}

TEST(Ros2FilterNode, ClockMessagesDecode) {
  const auto decode_clock = [](const std::vector<std::uint8_t>& cdr) {
    return io::decode_ros2_clock(cdr.data(), cdr.size()).seconds();
  };
  // rosgraph_msgs/Clock: little-endian, 1700000000 s and 250000000 ns.
  const std::vector<std::uint8_t> le = {0, 1, 0, 0, 0x00, 0xf1, 0x53, 0x65, 0x80, 0xb2, 0xe6, 0x0e};
  EXPECT_DOUBLE_EQ(decode_clock(le), 1700000000.25);
  std::vector<std::uint8_t> be = {0, 0, 0, 0, 0x65, 0x53, 0xf1, 0x00, 0x0e, 0xe6, 0xb2, 0x80};
  EXPECT_DOUBLE_EQ(decode_clock(be), 1700000000.25);
  EXPECT_THROW(decode_clock({0, 1, 0, 0, 1}), io::CdrError);
  be[8] = 0xff;  // nanosec >= 1e9.
  EXPECT_THROW(decode_clock(be), io::CdrError);
}

TEST(Ros2FilterNodeCore, AStaticSensorNeedsNoTransforms) {
  FilterNodeSettings s;
  s.static_sensor = true;
  FilterNodeCore core(s);
  const std::vector<FilterNodeOutput> out = core.scan(room_scan(1.0), 0.0, 0.0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].outcome, pipeline::ScanOutcome::kFiltered);
}

}  // namespace
}  // namespace dispel::ros2
