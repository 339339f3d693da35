// dispel odom and eval-trajectory on real recordings (optiodom: motion-capture truth; Husky:
// GPS), on the simulator's bags, on CSV input, and on bad input.
#include "dispel/jobs/odom_job.hpp"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/JointState.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "dispel/io/config_yaml.hpp"
#include "dispel/io/csv.hpp"
#include "dispel/io/scenario_yaml.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/jobs/sim_job.hpp"
#include "test_files.hpp"

namespace dispel::jobs {
namespace {

using namespace dispel::io;  // The formats the tests write and read.

using test::exists;
using test::source_path;
using test::temp_path;
void write_file(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

eval::TrajectoryErrors errors(const std::string& truth, const std::string& estimate,
                              double align_first_m = 0.0) {
  return eval::compare_trajectories(read_trajectory_csv(truth), read_trajectory_csv(estimate),
                                    {align_first_m});
}

OdomJobStats run(OdomJobOptions o, const std::string& model) {
  o.model = model;
  return run_odom_job(o);
}

// --- CSV input --------------------------------------------------------------------------------

TEST(OdomJob, CsvWheelsAndGyroOfAKnownArcGiveItsPose) {
  // 10 s on a circle of radius 2 m at 0.5 m/s (track 0.5 m), wheels at 50 Hz, gyro at 100 Hz.
  const double v = 0.5, w = 0.25, b = 0.5;
  std::ostringstream wheels, imu;
  wheels << "t,v_left,v_right\n";
  imu << "t,yaw_rate\n";
  for (int k = 0; k <= 1000; ++k) {
    imu << 0.01 * k << "," << w << "\n";
    if (k % 2 == 0) wheels << 0.01 * k << "," << v - 0.5 * w * b << "," << v + 0.5 * w * b << "\n";
  }
  OdomJobOptions o;
  o.wheels_csv = temp_path("arc_wheels.csv");
  o.imu_csv = temp_path("arc_imu.csv");
  o.output = temp_path("arc_trajectory.csv");
  write_file(o.wheels_csv, wheels.str());
  write_file(o.imu_csv, imu.str());
  for (const char* model : {"ct", "ct_euler", "omni", "dead_reckoning"}) {
    std::remove(o.output.c_str());
    const OdomJobStats s = run(o, model);
    EXPECT_EQ(s.wheel_messages, 501);
    EXPECT_EQ(s.imu_messages, 1001);
    EXPECT_EQ(s.rows, std::string(model) == "dead_reckoning" ? 501 : 1001) << model;
    ASSERT_TRUE(exists(o.output));
    EXPECT_FALSE(exists(o.output + ".partial"));
    const auto trajectory = read_trajectory_csv(o.output);
    ASSERT_EQ(static_cast<std::int64_t>(trajectory.size()), s.rows);
    const eval::TrajectoryPoint& end = trajectory.back();
    const double a = w * 10.0;  // 2.5 rad.
    EXPECT_NEAR(end.x_m, 2.0 * std::sin(a), 0.01) << model;
    EXPECT_NEAR(end.y_m, 2.0 - 2.0 * std::cos(a), 0.01) << model;
    EXPECT_NEAR(end.yaw_rad, a, 0.005) << model;
  }
  std::ifstream in(o.output);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "t,x,y,yaw,v,omega,var_x,var_y,var_yaw,var_v,var_omega");
}

TEST(OdomJob, JointStatesInRadiansPerSecondAreFoundByNameAndScaledByTheWheelRadius) {
  // A robot whose driver publishes the wheel joints right first, in rad/s, with a header stamp,
  // and an IMU whose yaw rate is on its -y axis.
  const std::string bag_path = temp_path("joint_states.bag");
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    for (int k = 0; k <= 100; ++k) {
      const ros::Time t(10.0 + 0.02 * k);
      sensor_msgs::JointState js;
      js.header.stamp = t;
      js.name = {"front_right_wheel_joint", "front_left_wheel_joint"};
      js.velocity = {6.0, 4.0};  // rad/s; wheels of 0.1 m: right 0.6 m/s, left 0.4 m/s.
      bag.write("/joint_states", t, js);
      sensor_msgs::Imu imu;
      imu.header.stamp = t;
      imu.angular_velocity.y = -0.4;  // (0.6 - 0.4) / 0.5 = 0.4 rad/s, on -y.
      bag.write("/imu/data", t, imu);
    }
  }
  OdomJobOptions o;
  o.input = bag_path;
  o.output = temp_path("joint_states.csv");
  o.config_path = temp_path("joint_states.yaml");
  write_file(*o.config_path,
             "odometry: {wheel_radius_m: 0.1, track_width_m: 0.5, imu_yaw_axis: -y}\n");
  const OdomJobStats s = run(o, "ct");
  EXPECT_EQ(s.wheel_source, "/joint_states");
  EXPECT_EQ(s.imu_source, "/imu/data");
  EXPECT_EQ(s.counters.count(OdometryEvent::kGated), 0);
  const OdometryEstimate& e = s.final_estimate;
  EXPECT_NEAR(e.v_mps, 0.5, 1e-3);
  EXPECT_NEAR(e.omega_radps, 0.4, 1e-3);
  EXPECT_NEAR(e.yaw_rad, 0.4 * 2.0, 0.01);
  std::remove(bag_path.c_str());
  std::remove(o.output.c_str());
}

// --- The simulator ----------------------------------------------------------------------------

TEST(OdomJob, OnTheSimulatedLawnmowerTheGyroCatchesTheWheelSlips) {
  // The lawnmower scenario for odometry, wheels without a left/right difference error (which no
  // gyro can tell from a turn, so it would dominate): its slips are what dead reckoning suffers
  // from, and what the fused filters gate away.
  sim::Scenario s = load_scenario(source_path("config/scenarios/odometry_lawnmower.yaml"));
  s.sensors.wheel_difference_error = 0.0;
  s.sensors.slips_per_minute = 3.0;
  const std::string bag = temp_path("odometry_lawnmower.bag");
  write_simulation(sim::simulate(s, 4, 120.0), s, bag);
  OdomJobOptions o;
  o.input = bag;
  o.truth_csv = temp_path("lawnmower_truth.csv");
  std::map<std::string, eval::TrajectoryErrors> e;
  std::map<std::string, OdomJobStats> stats;
  for (const char* model : {"dead_reckoning", "ct", "omni"}) {
    o.output = temp_path(std::string("lawnmower_") + model + ".csv");
    stats[model] = run(o, model);
    e[model] = errors(o.truth_csv, o.output);
    std::remove(o.output.c_str());
  }
  EXPECT_EQ(stats["ct"].wheel_source, "/wheels");
  EXPECT_EQ(stats["ct"].imu_source, "/imu");
  EXPECT_GT(stats["ct"].truth_rows, 5000);
  EXPECT_NEAR(e["ct"].path_length_m, 58.0, 3.0);
  // Each slip lasts 0.5 s (25 wheel samples); the filters refuse them.
  EXPECT_GE(stats["ct"].counters.wheels[static_cast<int>(OdometryEvent::kGated)], 25);
  EXPECT_EQ(stats["ct"].counters.count(OdometryEvent::kNumericalFailure), 0);
  for (const char* model : {"ct", "omni"}) {
    EXPECT_LT(e[model].final_position_error_m, 0.5 * e["dead_reckoning"].final_position_error_m)
        << model;
    EXPECT_LT(e[model].rmse_yaw_rad, 0.5 * e["dead_reckoning"].rmse_yaw_rad) << model;
  }
  RecordProperty("dead_reckoning_final_m",
                 std::to_string(e["dead_reckoning"].final_position_error_m));
  RecordProperty("ct_final_m", std::to_string(e["ct"].final_position_error_m));
  RecordProperty("omni_final_m", std::to_string(e["omni"].final_position_error_m));
  std::remove(bag.c_str());
  std::remove(o.truth_csv.c_str());
}

// --- Real recordings --------------------------------------------------------------------------

// One optiodom run (rows: time, x, y, theta, ticks right, ticks left at 20 Hz) as wheel-speed and
// truth CSVs. 2796.8 ticks per wheel revolution, wheels of 0.084 m (the session's metadata).
void convert_optiodom(const std::string& run, const std::string& wheels, const std::string& truth) {
  std::ifstream in(run);
  std::ofstream w(wheels), t(truth);
  w << "t,v_left,v_right\n";
  t << "t,x,y,yaw\n";
  constexpr double kMetresPerTick = 3.14159265358979323846 * 0.084 / (43.7 * 64.0);
  std::string line;
  double previous_t = 0.0;
  bool first = true;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 6u) << run;
    t << v[0] << "," << v[1] << "," << v[2] << "," << v[3] << "\n";
    if (!first) {
      const double dt = v[0] - previous_t;
      // Ticks counted over the cycle ending now: the mean speed, stamped at its middle.
      w << v[0] - 0.5 * dt << "," << v[5] * kMetresPerTick / dt << "," << v[4] * kMetresPerTick / dt
        << "\n";
    }
    previous_t = v[0];
    first = false;
  }
}

TEST(OdomJobOnRecordedData, OptiodomWheelsAloneEndNearTheMotionCaptureTruth) {
  // Wheels only: there is nothing to fuse, so the filters must follow dead reckoning (the gate
  // stays out of the way without a gyro) and end where it ends.
  const std::string cfg = temp_path("optiodom.yaml");
  write_file(cfg, "odometry: {track_width_m: 0.2}\n");
  int runs = 0;
  for (const char* session :
       {"square/230620202042/230620202042", "circular/231220200121/231220200121"}) {
    for (int r = 1; r <= 6; ++r) {
      char name[16];
      std::snprintf(name, sizeof name, "_run-%02d.csv", r);
      const std::string run_file = source_path(std::string("data/optiodom/") + session + name);
      if (!exists(run_file)) continue;
      OdomJobOptions o;
      o.wheels_csv = temp_path("optiodom_wheels.csv");
      o.config_path = cfg;
      const std::string truth = temp_path("optiodom_truth.csv");
      convert_optiodom(run_file, o.wheels_csv, truth);
      std::map<std::string, eval::TrajectoryErrors> e;
      for (const char* model : {"dead_reckoning", "ct", "omni"}) {
        o.output = temp_path("optiodom_estimate.csv");
        const OdomJobStats s = run(o, model);
        EXPECT_EQ(s.counters.count(OdometryEvent::kGated), 0);
        e[model] = errors(truth, o.output);
      }
      EXPECT_LT(e["dead_reckoning"].final_position_error_m, 0.2) << run_file;
      for (const char* model : {"ct", "omni"}) {
        EXPECT_NEAR(e[model].final_position_error_m, e["dead_reckoning"].final_position_error_m,
                    0.01)
            << run_file << " " << model;
      }
      ++runs;
    }
  }
  EXPECT_EQ(runs, 12);
}

TEST(OdomJobOnRecordedData, HuskyWheelsAndGyroFollowTheGpsTrackOnceTheImuAxisIsRight) {
  // robot_localization's test1.bag: a Husky outdoors, 395 s, wheel odometry (twist) and an IMU
  // mounted so that its y axis points up; GPS is the only reference (east/north, aligned on the
  // first 20 m of the track).
  const std::string bag = source_path("data/robot_localization/test1.bag");
  OdomJobOptions o;
  o.input = bag;
  o.truth_topic = "/fix";
  o.truth_csv = temp_path("husky_gps.csv");
  o.output = temp_path("husky.csv");
  o.config_path = temp_path("husky.yaml");
  write_file(*o.config_path, "odometry: {imu_yaw_axis: y, track_width_m: 0.555}\n");
  const OdomJobStats dr = run(o, "dead_reckoning");
  EXPECT_EQ(dr.wheel_source, "/husky_velocity_controller/odom");
  EXPECT_EQ(dr.wheel_messages, 3952);
  EXPECT_EQ(dr.truth_rows, 989);
  const eval::TrajectoryErrors e_dr = errors(o.truth_csv, o.output, 20.0);
  const OdomJobStats ct = run(o, "ct");
  EXPECT_EQ(ct.imu_source, "/imu/data");
  EXPECT_EQ(ct.imu_messages, 11865);
  EXPECT_EQ(ct.counters.count(OdometryEvent::kNumericalFailure), 0);
  const eval::TrajectoryErrors e_ct = errors(o.truth_csv, o.output, 20.0);
  EXPECT_TRUE(std::isnan(e_ct.rmse_yaw_rad));  // GPS has no heading.
  EXPECT_NEAR(e_ct.path_length_m, 395.6, 1.0);
  EXPECT_LT(e_dr.rmse_position_m, 12.0);  // Measured 8.2 m.
  EXPECT_LT(e_ct.rmse_position_m, 15.0);  // Measured 10.3 m.
  // The same with the gyro's z axis, which on this IMU does not turn with the robot.
  write_file(*o.config_path, "odometry: {track_width_m: 0.555}\n");
  run(o, "ct");
  EXPECT_GT(errors(o.truth_csv, o.output, 20.0).rmse_position_m, 4.0 * e_ct.rmse_position_m);
  RecordProperty("dead_reckoning_final_m", std::to_string(e_dr.final_position_error_m));
  RecordProperty("ct_final_m", std::to_string(e_ct.final_position_error_m));
  std::remove(o.output.c_str());
  std::remove(o.truth_csv.c_str());
}

// --- Bad input --------------------------------------------------------------------------------

void expect_job_error(const OdomJobOptions& o, const std::string& expected) {
  try {
    run_odom_job(o);
    ADD_FAILURE() << "accepted; expected: " << expected;
  } catch (const JobError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
  EXPECT_FALSE(exists(o.output));
  EXPECT_FALSE(exists(o.output + ".partial"));
}

TEST(OdomJobInput, BadInputIsAOneLineErrorAndWritesNothing) {
  OdomJobOptions o;
  o.output = temp_path("bad_input.csv");
  std::remove(o.output.c_str());
  o.input = temp_path("no_such.bag");
  expect_job_error(o, "no_such.bag: not a readable ROS 1 bag");
  const std::string text = temp_path("not_a_bag.bag");
  write_file(text, "hello\n");
  o.input = text;
  expect_job_error(o, "not a readable ROS 1 bag");
  o.input = source_path("data/leg_tracker/demo_stationary_simple_environment.bag");
  expect_job_error(o,
                   "which topic holds the wheel speeds? (JointState topics: none; Odometry "
                   "topics: none)");
  o.wheel_topic = "/scan";
  expect_job_error(o, "no sensor_msgs/JointState or nav_msgs/Odometry topic /scan");
  o.wheel_topic.clear();
  o.wheels_csv = temp_path("w.csv");
  expect_job_error(o, "either a bag or --wheels-csv");
  o.input.clear();
  write_file(o.wheels_csv, "time,left,right\n0,0,0\n");
  expect_job_error(o, "w.csv: the header must name the columns t,v_left,v_right");
  write_file(o.wheels_csv, "t,v_left,v_right\n0,0.1,0.1\n0.02,0.1\n");
  expect_job_error(o, "w.csv:3: 3 values expected, got 2");
  write_file(o.wheels_csv, "t,v_left,v_right\n0,0.1,0.1\n0.02,abc,0.1\n");
  expect_job_error(o, "w.csv:3: v_left 'abc' is not a number");
  write_file(o.wheels_csv, "t,v_left,v_right\n");
  expect_job_error(o, "w.csv: no wheel speeds");
  write_file(o.wheels_csv, "t,v_left,v_right\n0,0.1,0.1\n0.02,0.1,0.1\n");
  o.config_path = temp_path("bad_odometry.yaml");
  write_file(*o.config_path, "odometry: {track_width_m: 0}\n");
  expect_job_error(o, "odometry.track_width_m must be");
  write_file(*o.config_path, "odometry: {imu_yaw_axis: w}\n");
  expect_job_error(o, "odometry.imu_yaw_axis must be one of x, -x, y, -y, z, -z, got 'w'");
  write_file(*o.config_path, "odometry: {track_widht_m: 0.5}\n");
  expect_job_error(o, "unknown key 'odometry.track_widht_m'");
  o.config_path.reset();
  o.model = "ekf";
  expect_job_error(o, "--model must be one of ct, ct_euler, omni, dead_reckoning, got 'ekf'");
  o.model.reset();
  // Non-finite and out-of-order rows are counted, not fatal.
  write_file(o.wheels_csv,
             "t,v_left,v_right\n0,0.1,0.1\n0.02,nan,0.1\n0.01,0.1,0.1\n0.04,0.1,0.1\n");
  const OdomJobStats s = run_odom_job(o);
  EXPECT_EQ(s.counters.wheels[static_cast<int>(OdometryEvent::kRejectedNonFinite)], 1);
  EXPECT_EQ(s.stamps_out_of_order, 1);
  EXPECT_EQ(s.rows, 3);
  std::remove(o.output.c_str());
}

TEST(OdometrySettings, TheOdometrySectionIsReadAndTheFiltersKeysLeftAlone) {
  const OdometrySettings s = parse_odometry_settings(
      "segmentation: {min_points: 4}\n"
      "odometry: {model: omni, track_width_m: 0.3, wheel_radius_m: 0.05, imu_yaw_axis: -y,\n"
      "           left_wheel_joint: wheel_l, gate_probability: 0}\n",
      "both.yaml");
  EXPECT_EQ(s.filter.model, OdometryModel::kOmni);
  EXPECT_EQ(s.filter.track_width_m, 0.3);
  EXPECT_EQ(s.filter.gate_probability, 0.0);
  EXPECT_EQ(s.wheel_radius_m, 0.05);
  EXPECT_EQ(s.left_wheel_joint, "wheel_l");
  EXPECT_EQ(s.imu_yaw_axis, 1);
  EXPECT_EQ(s.imu_yaw_sign, -1.0);
  // And the filter's parser accepts the same file.
  EXPECT_EQ(parse_filter_config("segmentation: {min_points: 4}\nodometry: {model: omni}\n", "f")
                .segmentation.min_points,
            4);
  const OdometrySettings defaults = parse_odometry_settings("", "empty.yaml");
  EXPECT_EQ(defaults.filter.track_width_m, OdometryConfig{}.track_width_m);
}

TEST(OdometrySettings, TheShippedDefaultFileHoldsTheDefaults) {
  const OdometrySettings s = load_odometry_settings(source_path("config/default.yaml"));
  const OdometryConfig d;
  const OdometryConfig& c = s.filter;
  EXPECT_EQ(c.model, d.model);
  EXPECT_EQ(c.track_width_m, d.track_width_m);
  EXPECT_EQ(c.linear_velocity_variance_m2ps3, d.linear_velocity_variance_m2ps3);
  EXPECT_EQ(c.yaw_rate_variance_rad2ps3, d.yaw_rate_variance_rad2ps3);
  EXPECT_EQ(c.ukf_alpha, d.ukf_alpha);
  EXPECT_EQ(c.ukf_beta, d.ukf_beta);
  EXPECT_EQ(c.ukf_kappa, d.ukf_kappa);
  EXPECT_EQ(c.wheel_velocity_variance_m2ps2, d.wheel_velocity_variance_m2ps2);
  EXPECT_EQ(c.wheel_yaw_rate_variance_rad2ps2, d.wheel_yaw_rate_variance_rad2ps2);
  EXPECT_EQ(c.wheel_lateral_velocity_variance_m2ps2, d.wheel_lateral_velocity_variance_m2ps2);
  EXPECT_EQ(c.imu_yaw_rate_variance_rad2ps2, d.imu_yaw_rate_variance_rad2ps2);
  EXPECT_EQ(c.imu_smoothing, d.imu_smoothing);
  EXPECT_EQ(c.gyro_bias_enabled, d.gyro_bias_enabled);
  EXPECT_EQ(c.gyro_bias_initial_variance_rad2ps2, d.gyro_bias_initial_variance_rad2ps2);
  EXPECT_EQ(c.gyro_bias_random_walk_variance_rad2ps3, d.gyro_bias_random_walk_variance_rad2ps3);
  EXPECT_EQ(c.gate_probability, d.gate_probability);
  EXPECT_EQ(c.gate_override_after_s, d.gate_override_after_s);
  EXPECT_EQ(c.gate_agreement_radps, d.gate_agreement_radps);
  EXPECT_EQ(c.gate_agreement_window_s, d.gate_agreement_window_s);
  EXPECT_EQ(c.gate_wheels_without_imu, d.gate_wheels_without_imu);
  EXPECT_EQ(c.max_time_step_s, d.max_time_step_s);
  EXPECT_EQ(c.initial_position_variance_m2, d.initial_position_variance_m2);
  EXPECT_EQ(c.initial_yaw_variance_rad2, d.initial_yaw_variance_rad2);
  EXPECT_EQ(c.initial_velocity_variance_m2ps2, d.initial_velocity_variance_m2ps2);
  EXPECT_EQ(c.initial_yaw_rate_variance_rad2ps2, d.initial_yaw_rate_variance_rad2ps2);
  EXPECT_EQ(s.wheel_radius_m, 0.0);
  EXPECT_EQ(s.imu_yaw_axis, 2);
  EXPECT_EQ(s.imu_yaw_sign, 1.0);
}

}  // namespace
}  // namespace dispel::jobs
