#include "dispel/jobs/filter_job.hpp"

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/LaserScan.h>
#include <sys/stat.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "bag_contents.hpp"
#include "dispel/io/recording_motion.hpp"
#include "dispel/io/ros1_messages.hpp"
#include "dispel/sim/raycast.hpp"
#include "still_scanner_rates.hpp"
#include "test_files.hpp"

namespace dispel::jobs {
namespace {

using namespace dispel::io;  // The formats the tests write and read.

constexpr double kDeg = kPi / 180.0;

using test::exists;
using test::source_path;
using test::temp_path;

using test::BagContents;
using test::read_bag;

// --- The recorded leg_tracker bag -----------------------------------------------------------

// Walls kept and walkers removed (test::walls_and_walkers) by `dispel filter --static-sensor
// --scale-to-scanner [--config CONFIG]` on the recording, with every message copied unchanged.
void filter_recorded_bag(const std::optional<std::string>& config, test::WallsAndWalkers& rates) {
  FilterJobOptions o;
  o.input = source_path("data/leg_tracker/demo_stationary_simple_environment.bag");
  o.output = temp_path("leg_tracker_filtered.bag");
  o.static_sensor = true;
  o.scale_to_scanner = true;
  if (config) o.config_path = source_path(*config);
  // (temp_path is this test process's own: the two tests that call this may run at once.)
  const FilterJobStats stats = run_filter_job(o);
  EXPECT_EQ(stats.scans, 1265);
  EXPECT_EQ(stats.scans_filtered, 1265);
  EXPECT_EQ(stats.config.segmentation.min_points, 4);
  // A still scanner's pose is exact: its scans are not aligned (people walking past turned the
  // registered pose by 0.7 degrees).
  EXPECT_FALSE(stats.config.registration.align);
  EXPECT_EQ(stats.counters.scans_registered, 0);
  ASSERT_TRUE(exists(o.output));
  EXPECT_FALSE(exists(o.output + ".partial"));

  const BagContents in = read_bag(o.input);
  const BagContents out = read_bag(o.output);
  // The scans, the filtered scans, their labels and (when the registration is on) their poses.
  const bool registered = stats.config.registration.enabled;
  EXPECT_EQ(out.count.size(), registered ? 4u : 3u);
  if (registered) {
    EXPECT_EQ(out.count.at("/scan_pose"), 1265u);
  }
  const auto& scans = out.scans.at("/scan");
  const auto& filtered = out.scans.at("/scan_filtered");
  const auto& labels = out.scans.at("/scan_labels");
  ASSERT_EQ(scans.size(), 1265u);
  ASSERT_EQ(filtered.size(), 1265u);
  ASSERT_EQ(labels.size(), 1265u);
  const auto& original = in.scans.at("/scan");
  for (std::size_t k = 0; k < scans.size(); ++k) {
    // The input is copied unchanged, bit for bit (it holds NaN, so no == on floats).
    ASSERT_EQ(scans[k].header.stamp, original[k].header.stamp);
    ASSERT_EQ(scans[k].ranges.size(), original[k].ranges.size());
    ASSERT_EQ(std::memcmp(scans[k].ranges.data(), original[k].ranges.data(),
                          scans[k].ranges.size() * sizeof(float)),
              0);
    EXPECT_EQ(filtered[k].header.stamp, original[k].header.stamp);
    EXPECT_EQ(filtered[k].header.frame_id, original[k].header.frame_id);
    EXPECT_EQ(labels[k].header.stamp, original[k].header.stamp);
    ASSERT_EQ(labels[k].intensities.size(), original[k].ranges.size());
  }

  for (std::size_t k = 0; k < original.size(); ++k) {
    for (std::size_t i = 0; i < original[k].ranges.size(); ++i) {
      if (!std::isfinite(original[k].ranges[i])) continue;
      EXPECT_EQ(std::isnan(filtered[k].ranges[i]),
                labels[k].intensities[i] == 1.0F || labels[k].intensities[i] == 2.0F);
    }
  }
  rates = test::walls_and_walkers(
      original, [&](std::size_t k, std::size_t i) { return std::isnan(filtered[k].ranges[i]); });
  EXPECT_GT(rates.wall_beams, 30000);
  EXPECT_GT(rates.walker_beams, 10000);
  std::remove(o.output.c_str());
}

TEST(FilterJobOnRecordedBag, RemovesWalkersKeepsWallsAndCopiesEveryMessage) {
  test::WallsAndWalkers d;
  ASSERT_NO_FATAL_FAILURE(filter_recorded_bag(std::nullopt, d));  // dispel's default.
  RecordProperty("wall_beams_kept", std::to_string(d.walls_kept_rate()));
  RecordProperty("walker_beams_removed", std::to_string(d.walkers_removed_rate()));
  // Measured 1.000 and 0.941 (0.935 before free_space.mark_beside_dynamic); legs beyond 4 m
  // cover under 4 beams, the scaled N_min, and are not objects at all.
  EXPECT_GE(d.walls_kept_rate(), 0.99);
  EXPECT_GE(d.walkers_removed_rate(), 0.88);
}

TEST(FilterJobOnRecordedBag, TheThesisFilterKeepsTheWallsAndMissesTheWalkers) {
  test::WallsAndWalkers t;
  ASSERT_NO_FATAL_FAILURE(filter_recorded_bag(std::string("config/thesis.yaml"), t));
  RecordProperty("wall_beams_kept", std::to_string(t.walls_kept_rate()));
  RecordProperty("walker_beams_removed", std::to_string(t.walkers_removed_rate()));
  // Its nearest-neighbour matching (to where a track was last seen) keeps few walkers long enough
  // to collect L_d scans of motion (DynamicFilterOnRecordedScans.TheThesisFilter...).
  EXPECT_GE(t.walls_kept_rate(), 0.99);
  EXPECT_LT(t.walkers_removed_rate(), 0.5);
}

// --- A moving robot, with odometry and the laser mount ---------------------------------------

struct SimBagOptions {
  bool mount_on_tf_static = true;
  bool odom_on_tf = true;
};

// A robot drives along x at 0.4 m/s in a hall while a person crosses in front of it. The laser is
// mounted 0.3 m ahead of base_link, turned by 0.1 rad.
std::string write_sim_bag(const std::string& name, const SimBagOptions& opt) {
  const std::string path = temp_path(name);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const Pose2 mount{0.3, 0.0, 0.1};
  if (opt.mount_on_tf_static) {
    tf2_msgs::TFMessage tf;
    geometry_msgs::TransformStamped t;
    t.header.stamp = to_ros_time(100.0);
    t.header.frame_id = "base_link";
    t.child_frame_id = "laser";
    t.transform.translation.x = mount.x_m;
    t.transform.rotation = quaternion_from_yaw(mount.yaw_rad);
    tf.transforms = {t};
    bag.write("/tf_static", t.header.stamp, tf);
  }
  sim::World world;
  world.segments = {
      {{-5, -6}, {15, -6}}, {{15, -6}, {15, 6}}, {{15, 6}, {-5, 6}}, {{-5, 6}, {-5, -6}}};
  world.circles = {{{4.0, 2.5}, 0.3}};
  const sim::ScanGeometry g{-135.0 * kDeg, 0.25 * kDeg, 1081, 0.05F, 30.0F};
  for (int k = 0; k < 120; ++k) {
    const double t = 100.0 + 0.05 * k;
    const Pose2 base{0.4 * 0.05 * k, 0.0, 0.0};
    nav_msgs::Odometry odom;
    odom.header.stamp = to_ros_time(t);
    odom.header.frame_id = "odom";
    odom.child_frame_id = "base_link";
    odom.pose.pose.position.x = base.x_m;
    odom.pose.pose.orientation = quaternion_from_yaw(base.yaw_rad);
    bag.write("/odom", odom.header.stamp, odom);
    if (opt.odom_on_tf) {
      tf2_msgs::TFMessage tf;
      geometry_msgs::TransformStamped tr;
      tr.header = odom.header;
      tr.child_frame_id = "base_link";
      tr.transform.translation.x = base.x_m;
      tr.transform.rotation = odom.pose.pose.orientation;
      tf.transforms = {tr};
      bag.write("/tf", odom.header.stamp, tf);
    }
    sim::World now = world;
    now.circles.push_back({{6.0, -3.0 + 1.2 * 0.05 * k}, 0.2});  // The person.
    LaserScan scan = sim::raycast(now, base * mount, g);
    scan.stamp_s = t;
    const sensor_msgs::LaserScan msg = to_ros(scan, "laser");
    bag.write("/scan", msg.header.stamp, msg);
  }
  return path;
}

// --- A real robot driving without odometry ---------------------------------------------------

// negative_2.bag (angusleigh/leg_tracker, BSD): a robot driving through a building with three
// 768-beam lasers, no odometry and no people: every beam removed is a false removal. Each laser
// is filtered laser-only (the recording has no odometry topic: the job says so), every scan
// registers to the map of the earlier ones, and at most 0.16 % of the valid beams are removed.
// (Measured 0.10-0.29 % on December 2, 0.22-0.71 % before the free-space verdict was weighed
// again; the target is 0.2 %: docs/results.md.)
TEST(FilterJobLaserOnly, RealRobotWithoutOdometryOrPeopleKeepsItsWalls) {
  for (const std::string laser : {"/left_scan", "/right_scan", "/rear_scan"}) {
    FilterJobOptions o;
    o.input = source_path("data/leg_tracker/negative_2.bag");
    o.output = temp_path("negative_2" + laser.substr(1) + ".bag");
    o.scan_topic = laser;
    std::string notice;
    const FilterJobStats stats =
        run_filter_job(o, {}, nullptr, [&](const std::string& n) { notice = n; });
    EXPECT_TRUE(stats.laser_only);
    EXPECT_NE(notice.find("no nav_msgs/Odometry topic: filtering laser-only"), std::string::npos)
        << notice;
    EXPECT_GE(stats.scans, 434);
    EXPECT_EQ(stats.scans_filtered, stats.scans) << laser;
    EXPECT_EQ(stats.counters.scans_without_odometry, stats.scans);
    EXPECT_GE(stats.counters.scans_registered, stats.scans - 5) << laser;
    EXPECT_LE(stats.counters.registration_fallbacks, 5) << laser;
    const BagContents out = read_bag(o.output);
    EXPECT_EQ(out.count.at(laser + "_pose"), static_cast<std::size_t>(stats.scans));
    std::int64_t valid = 0, removed = 0;
    for (const sensor_msgs::LaserScan& l : out.scans.at(laser + "_labels")) {
      for (const float label : l.intensities) {
        if (label == static_cast<float>(BeamLabel::kInvalid)) continue;
        ++valid;
        removed += label == static_cast<float>(BeamLabel::kDynamic) ||
                   label == static_cast<float>(BeamLabel::kUnknown);
      }
    }
    EXPECT_GT(valid, 200000) << laser;
    // No people: every removed beam is a false removal. The target: at most 0.2 % per laser.
    // 0.14 / 0.08 / 0.04 % today; 0.19 / 0.13 / 0.05 % before free_space.require_unseen, whose
    // places that returned before are no free-space evidence without odometry (it turned away
    // objects on every laser); docs/results.md.
    EXPECT_LE(static_cast<double>(removed), 0.0016 * static_cast<double>(valid))
        << laser << ": " << removed << " of " << valid << " valid beams removed";
    EXPECT_GT(stats.counters.free_space_seen_before, 0) << laser;
    std::remove(o.output.c_str());
  }
}

TEST(FilterJob, MovingRobotWithOdometryAndMountRemovesThePersonOnly) {
  FilterJobOptions o;
  o.input = write_sim_bag("moving.bag", {});
  o.output = temp_path("moving_filtered.bag");
  o.compression = Compression::kLz4;
  const FilterJobStats stats = run_filter_job(o);
  EXPECT_EQ(stats.scans, 120);
  EXPECT_EQ(stats.scans_filtered, 120);
  EXPECT_GT(stats.counters.beams_removed_dynamic, 0);
  const BagContents out = read_bag(o.output);
  EXPECT_EQ(out.count.at("/odom"), 120u);
  EXPECT_EQ(out.count.at("/tf"), 120u);
  EXPECT_EQ(out.count.at("/tf_static"), 1u);
  const auto& labels = out.scans.at("/scan_labels");
  // After 2 s the person (nearer than 8 m on the right half) is removed and the hall is not.
  std::int64_t person = 0, person_removed = 0, hall_removed = 0;
  for (std::size_t k = 40; k < labels.size(); ++k) {
    const Pose2 base{0.4 * 0.05 * static_cast<double>(k), 0.0, 0.0};
    const Pose2 laser = base * Pose2{0.3, 0.0, 0.1};
    const Eigen::Vector2d walker(6.0, -3.0 + 1.2 * 0.05 * static_cast<double>(k));
    for (std::size_t i = 0; i < labels[k].ranges.size(); ++i) {
      const double r = labels[k].ranges[i];
      if (!std::isfinite(r)) continue;
      const double b = labels[k].angle_min + labels[k].angle_increment * static_cast<double>(i);
      const Eigen::Vector2d p = laser.apply({r * std::cos(b), r * std::sin(b)});
      const bool removed = labels[k].intensities[i] == 1.0F;
      if ((p - walker).norm() < 0.25) {
        ++person;
        person_removed += removed ? 1 : 0;
      } else if ((p - Eigen::Vector2d(4.0, 2.5)).norm() > 0.35) {
        hall_removed += removed ? 1 : 0;  // Walls; the pillar is checked below.
      }
    }
  }
  EXPECT_GT(person, 500);
  EXPECT_GT(static_cast<double>(person_removed), 0.9 * static_cast<double>(person));
  EXPECT_EQ(hall_removed, 0);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

TEST(FilterJob, MissingMountIsAnErrorUnlessTheSensorIsStatic) {
  FilterJobOptions o;
  o.input = write_sim_bag("no_mount.bag", {false, true});
  o.output = temp_path("no_mount_filtered.bag");
  try {
    run_filter_job(o);
    ADD_FAILURE();
  } catch (const JobError& e) {
    EXPECT_NE(std::string(e.what()).find("no transform from base_link to laser"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(exists(o.output));
  o.static_sensor = true;
  EXPECT_NO_THROW(run_filter_job(o));
  EXPECT_TRUE(exists(o.output));
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

// --- Bad input --------------------------------------------------------------------------------

void expect_job_error(const FilterJobOptions& o, const std::string& expected) {
  try {
    run_filter_job(o);
    ADD_FAILURE() << "accepted " << o.input;
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_FALSE(exists(o.output)) << "an output was written for " << o.input;
  EXPECT_FALSE(exists(o.output + ".partial"));
}

TEST(FilterJobInput, BadRecordingsAndConfigurationsAreOneLineErrorsAndWriteNothing) {
  const std::string real = source_path("data/leg_tracker/demo_stationary_simple_environment.bag");
  FilterJobOptions o;
  o.output = temp_path("never.bag");
  o.static_sensor = true;

  o.input = temp_path("does_not_exist.bag");
  expect_job_error(o, "No such file");

  o.input = temp_path("not_a_bag.bag");
  std::ofstream(o.input) << "this is not a bag\n";
  expect_job_error(o, "not a readable ROS 1 bag");

  // The first half of a real bag: the index at its end is gone.
  o.input = temp_path("truncated.bag");
  {
    std::ifstream in(real, std::ios::binary);
    std::stringstream all;
    all << in.rdbuf();
    const std::string bytes = all.str();
    std::ofstream(o.input, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  expect_job_error(o, "truncated.bag");

  o.input = real;
  o.scan_topic = "/front_scan";
  expect_job_error(o, "no sensor_msgs/LaserScan topic /front_scan (LaserScan topics: /scan)");
  o.scan_topic = "/scan";

  // Without odometry: laser-only when the registration is on (dispel's default); the thesis's
  // filter, which has none, needs the odometry; the odometry topic named and not there, when the
  // recording has other odometry, is an error (FilterJobLaserOnly tests the laser-only runs).
  o.static_sensor = false;
  o.config_path = source_path("config/thesis.yaml");
  expect_job_error(o, "no nav_msgs/Odometry topic /odom");
  o.odom_topic = "none";
  expect_job_error(o, "--odom-topic none needs the scan registration");
  o.odom_topic = "/odom";
  o.config_path.reset();
  o.static_sensor = true;

  o.config_path = temp_path("bad_key.yaml");
  std::ofstream(*o.config_path) << "segmentation:\n  cluster_gapm: 0.1\n";
  expect_job_error(o, "unknown key 'segmentation.cluster_gapm'");
  o.config_path = temp_path("negative_eps.yaml");
  std::ofstream(*o.config_path) << "segmentation:\n  cluster_gap_m: -0.1\n";
  expect_job_error(o, "segmentation.cluster_gap_m must be");
}

TEST(FilterJobInput, CancellingLeavesNoOutput) {
  FilterJobOptions o;
  o.input = source_path("data/leg_tracker/demo_stationary_simple_environment.bag");
  o.output = temp_path("cancelled.bag");
  o.static_sensor = true;
  std::atomic<bool> cancel{false};
  int calls = 0;
  EXPECT_THROW(run_filter_job(
                   o,
                   [&](double) {
                     if (++calls == 2) cancel.store(true);  // Partway through the second pass.
                   },
                   &cancel),
               JobCancelled);
  EXPECT_GE(calls, 2);
  EXPECT_FALSE(exists(o.output));
  EXPECT_FALSE(exists(o.output + ".partial"));
}

// --- CARMEN logs ------------------------------------------------------------------------------

// A FLASER log of a robot driving past a walking person, and its odometry: 120 scans, one every
// @p step_s seconds from 5000 s, and a malformed line.
void write_walk_log(const std::string& log_path, double step_s) {
  std::ofstream log(log_path);
  log << "# CARMEN log written by the test\n";
  sim::World world;
  world.segments = {{{-5, -6}, {15, -6}}, {{15, -6}, {15, 6}}, {{15, 6}, {-5, 6}}};
  const sim::ScanGeometry g{-kPi / 2.0, kPi / 360.0, 361, 0.001F, 80.0F};
  for (int k = 0; k < 120; ++k) {
    const double t = 5000.0 + step_s * k;
    const Pose2 laser{0.02 * k, 0.0, 0.0};
    sim::World now = world;
    now.circles = {{{6.0, -3.0 + 0.06 * k}, 0.2}};
    const LaserScan s = sim::raycast(now, laser, g);
    log << "ODOM " << laser.x_m << " 0 0 0.4 0 0 " << std::fixed << t << " host " << t << "\n";
    log << "FLASER 361";
    for (float r : s.ranges_m) log << ' ' << (std::isfinite(r) ? r : 81.91F);
    log << ' ' << laser.x_m << " 0 0 " << laser.x_m << " 0 0 " << t << " host " << t << "\n";
  }
  log << "FLASER garbage\n";
}

TEST(FilterJob, CarmenLogBecomesABagWithFilteredScans) {
  const std::string log_path = temp_path("walk.log");
  write_walk_log(log_path, 0.05);
  FilterJobOptions o;
  o.input = log_path;
  o.output = temp_path("walk.bag");
  const FilterJobStats stats = run_filter_job(o);
  EXPECT_EQ(stats.input_format, "carmen");
  EXPECT_EQ(stats.scans, 120);
  EXPECT_EQ(stats.malformed_lines, 1);
  EXPECT_GT(stats.counters.beams_removed_dynamic, 300);
  EXPECT_EQ(stats.scans_reset, 0);
  EXPECT_FALSE(stats.mostly_unfiltered);
  EXPECT_EQ(stats.warning, "");
  const BagContents out = read_bag(o.output);
  EXPECT_EQ(out.count.at("/scan"), 120u);
  EXPECT_EQ(out.count.at("/scan_filtered"), 120u);
  EXPECT_EQ(out.count.at("/scan_labels"), 120u);
  EXPECT_EQ(out.count.at("/odom"), 120u);         // The laser lines' poses.
  EXPECT_EQ(out.count.at("/carmen_odom"), 120u);  // The ODOM lines.
  EXPECT_EQ(out.count.at("/tf_static"), 1u);
  EXPECT_EQ(stats.stamp_offset_s, 0.0);  // Stamps from 5000 s: kept.
  EXPECT_EQ(out.scans.at("/scan").front().header.frame_id, "laser");
  std::remove(log_path.c_str());
  std::remove(o.output.c_str());
}

// Issue 16: a subsampled log (848 of 910 scans reset the filter) was filtered into nothing while
// the summary said only "0 dynamic removed". Now the job says so.
TEST(FilterJob, ASparseLogWhoseScansMostlyResetTheFilterIsReported) {
  const std::string log_path = temp_path("sparse.log");
  write_walk_log(log_path, 2.0);  // Scans 2 s apart; max_time_gap_s is 1 s.
  FilterJobOptions o;
  o.input = log_path;
  o.output = temp_path("sparse.bag");
  const FilterJobStats stats = run_filter_job(o);
  EXPECT_EQ(stats.scans, 120);
  EXPECT_EQ(stats.scans_reset, 119);
  EXPECT_TRUE(stats.mostly_unfiltered);
  EXPECT_NE(stats.warning.find("119 of 120 scans reset the filter (119 after a time gap above "
                               "max_time_gap_s 1 s"),
            std::string::npos)
      << stats.warning;
  EXPECT_EQ(stats.counters.beams_removed_dynamic, 0);
  std::remove(log_path.c_str());
  std::remove(o.output.c_str());
}

// Issue 16: the classic corrected logs count time from 0, and a bag holds no time 0: every one
// failed ("Tried to insert a message with time less than ros::TIME_MIN"). Now every stamp is
// shifted by 1 s, and the output carries what render and slam need: /odom with the pose the
// filter used and the laser's mount on /tf_static (read back by the same first pass as theirs).
TEST(FilterJob, ACarmenLogFromTimeZeroIsShiftedAndCarriesOdometryAndMount) {
  FilterJobOptions o;
  o.input = source_path("data/carmen/leg_tracker_from0.log");
  o.output = temp_path("from0.bag");
  std::string notice;
  const FilterJobStats stats =
      run_filter_job(o, {}, nullptr, [&](const std::string& n) { notice += n; });
  EXPECT_EQ(stats.scans, 100);
  EXPECT_EQ(stats.scans_filtered, 100);
  EXPECT_EQ(stats.stamp_offset_s, 1.0);
  EXPECT_NE(notice.find("counts time from 0: every stamp is shifted by +1 s"), std::string::npos)
      << notice;
  EXPECT_GT(stats.counters.beams_removed_dynamic, 100);
  const BagContents out = read_bag(o.output);
  EXPECT_EQ(out.count.at("/odom"), 100u);
  EXPECT_EQ(out.count.at("/tf_static"), 1u);
  const auto& scans = out.scans.at("/scan");
  ASSERT_EQ(scans.size(), 100u);
  EXPECT_EQ(scans.front().header.stamp, ros::Time(1, 0));
  EXPECT_NEAR((scans.back().header.stamp - scans.front().header.stamp).toSec(), 9.9, 0.05);

  const std::unique_ptr<io::RecordingReader> bag = open_recording(o.output);
  io::MotionQuery query;
  query.scan_topic = "/scan";
  query.pose_topic = "/odom";
  const io::RecordingMotion motion = io::read_motion(*bag, query, [] {});
  PoseLookup why = PoseLookup::kOk;
  EXPECT_TRUE(motion.sensor_pose(scans[10].header.stamp.toSec(), &why)) << pose_lookup_name(why);
  std::remove(o.output.c_str());
}

}  // namespace
}  // namespace dispel::jobs
