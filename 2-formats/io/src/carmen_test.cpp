#include "dispel/io/carmen.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "dispel/io/errors.hpp"

namespace dispel::io {
namespace {

std::string flaser(const std::vector<float>& ranges, double x, double y, double theta, double t) {
  std::ostringstream line;
  line << "FLASER " << ranges.size();
  for (float r : ranges) line << ' ' << r;
  line << ' ' << x << ' ' << y << ' ' << theta << ' ' << x << ' ' << y << ' ' << theta << ' '
       << std::fixed << t << " nohost " << t;
  return line.str();
}

TEST(CarmenLog, ReadsLaserAndOdometryLinesAndCountsTheRest) {
  std::vector<float> ranges(181, 5.0F);
  ranges[10] = 81.9F;  // Beyond the SICK's range: no return.
  std::stringstream log;
  log << "# a comment\n"
      << "PARAM robot_length 0.5 nohost 0.0\n"
      << "ODOM 1.0 2.0 0.5 0.1 0.0 0.0 100.0 nohost 100.0\n"
      << flaser(ranges, 1.0, 2.0, 0.5, 100.05) << "\n"
      << "RLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 100.06 nohost 100.06\n"
      << "ROBOTLASER1 0 -1.5708 3.1416 0.0174533 30.0 0.1 0 4 1.0 2.0 3.0 4.0 0 "
         "0.2 0.0 0.1 0.0 0.0 0.1 0.0 0.0 0.0 0.0 0.0 100.1 nohost 100.1\n"
      << "FLASER 181 1.0 2.0\n"                                // Truncated: malformed.
      << "ODOM 1.1 two 0.5 0.1 0.0 0.0 100.2 nohost 100.2\n";  // Malformed.
  const CarmenLog parsed = parse_carmen_log(log, "test.log");
  EXPECT_EQ(parsed.lines, 8);
  EXPECT_EQ(parsed.ignored_lines, 2);
  EXPECT_EQ(parsed.malformed_lines, 2);
  EXPECT_NE(parsed.first_malformed.find("line 7"), std::string::npos) << parsed.first_malformed;
  ASSERT_EQ(parsed.scans.size(), 3u);
  ASSERT_EQ(parsed.odometry.size(), 1u);
  EXPECT_DOUBLE_EQ(parsed.odometry[0].stamp_s, 100.0);
  EXPECT_DOUBLE_EQ(parsed.odometry[0].pose.y_m, 2.0);

  const CarmenScan& front = parsed.scans[0];
  EXPECT_EQ(front.kind, "FLASER");
  EXPECT_EQ(check_scan(front.scan), ScanIssue::kNone);
  EXPECT_EQ(front.scan.size(), 181u);
  EXPECT_NEAR(front.scan.angle_min_rad, -kPi / 2.0, 1e-12);
  EXPECT_NEAR(front.scan.angle_increment_rad, kPi / 180.0, 1e-12);
  EXPECT_TRUE(front.scan.is_valid(0));
  EXPECT_FALSE(front.scan.is_valid(10));
  EXPECT_DOUBLE_EQ(front.scan.stamp_s, 100.05);
  EXPECT_DOUBLE_EQ(front.laser_pose.yaw_rad, 0.5);

  EXPECT_NEAR(parsed.scans[1].laser_pose.yaw_rad, wrap_angle(kPi), 1e-12);  // Rear laser.
  const CarmenScan& robot = parsed.scans[2];
  EXPECT_EQ(robot.kind, "ROBOTLASER1");
  EXPECT_EQ(robot.scan.size(), 4u);
  EXPECT_NEAR(robot.scan.angle_increment_rad, 0.0174533, 1e-9);
  EXPECT_FLOAT_EQ(robot.scan.range_max_m, 30.0F);
  EXPECT_DOUBLE_EQ(robot.laser_pose.x_m, 0.2);
  EXPECT_DOUBLE_EQ(robot.scan.stamp_s, 100.1);
}

TEST(CarmenLog, AFileWithoutLaserLinesIsAnErrorNamingIt) {
  std::stringstream log("ODOM 1 2 3 0 0 0 1.0 host 1.0\nnot a carmen line\n");
  try {
    parse_carmen_log(log, "empty.log");
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("empty.log: no FLASER"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_carmen_log("/nonexistent.clf"), std::runtime_error);
}

// Issue 16: 5e9 s was written wrapped (705032704.5 s), 1e300 s became 0. A stamp a recording
// cannot hold refuses the log, naming the line; time 0 itself is a valid CARMEN stamp.
TEST(CarmenLog, AStampARecordingCannotHoldIsAnErrorNamingTheLine) {
  const std::string flaser = "FLASER 3 1 1 1 0 0 0 0 0 0 ";
  for (const std::string stamp : {"5e9", "4294967295", "-1", "1e300", "nan", "inf"}) {
    std::stringstream log(flaser + "0 host 0\n" + flaser + stamp + " host 0\n");
    try {
      parse_carmen_log(log, "t.log");
      ADD_FAILURE() << stamp;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), "t.log: line 2 (FLASER): ipc_timestamp '" + stamp +
                                           "' is not a time a recording can hold (0 to "
                                           "4294967295 s)");
    }
  }
  std::stringstream odom("ODOM 0 0 0 0 0 0 -5 host 0\n" + flaser + "0 host 0\n");
  EXPECT_THROW(parse_carmen_log(odom, "t.log"), InputError);
  std::stringstream from_zero(flaser + "0 host 0\n" + flaser + "4294967294.5 host 0\n");
  EXPECT_EQ(parse_carmen_log(from_zero, "t.log").scans.size(), 2u);
}

}  // namespace
}  // namespace dispel::io
