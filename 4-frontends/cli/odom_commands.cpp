#include "odom_commands.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "dispel/io/config_yaml.hpp"
#include "dispel/io/csv.hpp"
#include "dispel/jobs/filter_job.hpp"

namespace dispel::apps {

int run_odom(const OdomCommandOptions& o) {
  jobs::OdomJobStats s;
  try {
    s = jobs::run_odom_job(o.job);
  } catch (const std::exception& e) {
    std::cerr << "dispel odom: " << error_line(e.what()) << "\n";
    return 1;
  }
  const OdometryEstimate& e = s.final_estimate;
  if (o.json) {
    nlohmann::ordered_json events;
    for (std::size_t i = 0; i < kOdometryEventCount; ++i) {
      events[odometry_event_name(static_cast<OdometryEvent>(i))] = {
          {"wheels", s.counters.wheels[i]}, {"imu", s.counters.imu[i]}};
    }
    nlohmann::ordered_json j;
    j["model"] = s.model;
    j["wheel_source"] = s.wheel_source;
    j["imu_source"] = s.imu_source;
    j["wheel_messages"] = s.wheel_messages;
    j["imu_messages"] = s.imu_messages;
    j["stamps_out_of_order"] = s.stamps_out_of_order;
    j["malformed"] = s.malformed;
    j["events"] = events;
    j["rows"] = s.rows;
    j["truth_rows"] = s.truth_rows;
    j["track_width_m"] = s.track_width_m;
    j["final"] = {{"t", e.t_s}, {"x", e.x_m}, {"y", e.y_m}, {"yaw", e.yaw_rad}};
    std::cout << j.dump(2) << std::endl;
    return 0;
  }
  const auto gated = s.counters.count(OdometryEvent::kGated);
  const auto rejected = s.counters.count(OdometryEvent::kRejectedNonFinite) +
                        s.counters.count(OdometryEvent::kRejectedOutOfOrder);
  std::printf(
      "dispel odom (%s): %lld wheel and %lld IMU measurements, %lld gated, %lld rejected; "
      "final pose x %.3f m, y %.3f m, yaw %.4f rad at t %.3f s\nwrote %s (%lld rows)\n",
      s.model.c_str(), static_cast<long long>(s.wheel_messages),
      static_cast<long long>(s.imu_messages), static_cast<long long>(gated),
      static_cast<long long>(rejected), e.x_m, e.y_m, e.yaw_rad, e.t_s, o.job.output.c_str(),
      static_cast<long long>(s.rows));
  return 0;
}

int run_eval_trajectory(const EvalTrajectoryOptions& o) {
  eval::TrajectoryErrors e;
  try {
    e = eval::compare_trajectories(io::read_trajectory_csv(o.truth),
                                   io::read_trajectory_csv(o.estimate), {o.align_first_m});
  } catch (const std::exception& err) {
    std::cerr << "dispel eval-trajectory: " << error_line(err.what()) << "\n";
    return 1;
  }
  if (o.json) {
    // JSON has no NaN: a yaw error against a truth without yaw (GPS) is null.
    const auto number = [](double v) {
      return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
    };
    nlohmann::ordered_json j;
    j["rmse_position_m"] = e.rmse_position_m;
    j["rmse_x_m"] = e.rmse_x_m;
    j["rmse_y_m"] = e.rmse_y_m;
    j["rmse_yaw_rad"] = number(e.rmse_yaw_rad);
    j["final_position_error_m"] = e.final_position_error_m;
    j["final_yaw_error_rad"] = number(e.final_yaw_error_rad);
    j["max_position_error_m"] = e.max_position_error_m;
    j["max_yaw_error_rad"] = number(e.max_yaw_error_rad);
    j["path_length_m"] = e.path_length_m;
    j["compared"] = e.compared;
    j["outside"] = e.outside;
    j["alignment_rotation_rad"] = e.alignment_rotation_rad;
    std::cout << j.dump(2) << std::endl;
    return 0;
  }
  std::printf("%-28s %10s\n", "measure", "value");
  std::printf("%-28s %10.4f m (x %.4f m, y %.4f m)\n", "RMSE position", e.rmse_position_m,
              e.rmse_x_m, e.rmse_y_m);
  std::printf("%-28s %10.4f rad\n", "RMSE yaw", e.rmse_yaw_rad);
  std::printf("%-28s %10.4f m\n", "final position error", e.final_position_error_m);
  std::printf("%-28s %10.4f rad\n", "final yaw error", e.final_yaw_error_rad);
  std::printf("%-28s %10.4f m\n", "largest position error", e.max_position_error_m);
  std::printf("%-28s %10.4f rad\n", "largest yaw error", e.max_yaw_error_rad);
  std::printf("%-28s %10.3f m (%lld truth poses compared, %lld outside the estimate)\n",
              "path length", e.path_length_m, static_cast<long long>(e.compared),
              static_cast<long long>(e.outside));
  return 0;
}

}  // namespace dispel::apps
