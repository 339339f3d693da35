#include "dispel/io/config_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "dispel/io/text.hpp"

namespace dispel::io {
namespace {

using Setter = std::function<void(const YAML::Node&, const std::string& key)>;

// One line, however long the file's name and whatever yaml-cpp's message quotes.
[[noreturn]] void fail(const std::string& origin, const std::string& message) {
  throw ConfigError(one_line(origin + ": " + message));
}

template <typename T>
T scalar(const YAML::Node& node, const std::string& key, const std::string& origin,
         const char* kind) {
  if (!node.IsScalar()) fail(origin, key + " must be " + kind);
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    fail(origin, key + " must be " + kind + ", got " + quote(node.Scalar()));
  }
}

class Binder {
 public:
  explicit Binder(std::string origin) : origin_(std::move(origin)) {}

  void number(const std::string& key, double& field) {
    setters_[key] = [this, &field](const YAML::Node& n, const std::string& k) {
      field = scalar<double>(n, k, origin_, "a number");
    };
  }
  void integer(const std::string& key, int& field) {
    setters_[key] = [this, &field](const YAML::Node& n, const std::string& k) {
      field = scalar<int>(n, k, origin_, "an integer");
    };
  }
  void boolean(const std::string& key, bool& field) {
    setters_[key] = [this, &field](const YAML::Node& n, const std::string& k) {
      field = scalar<bool>(n, k, origin_, "true or false");
    };
  }
  template <typename E>
  void choice(const std::string& key, E& field, std::map<std::string, E> names) {
    setters_[key] = [this, &field, names](const YAML::Node& n, const std::string& k) {
      const auto word = scalar<std::string>(n, k, origin_, "a word");
      const auto it = names.find(word);
      if (it == names.end()) {
        std::string options;
        for (const auto& [name, value] : names) options += (options.empty() ? "" : ", ") + name;
        fail(origin_, k + " must be one of " + options + ", got " + quote(word));
      }
      field = it->second;
    };
  }
  void custom(const std::string& key, Setter setter) { setters_[key] = std::move(setter); }

  // Applies a mapping node; every key must be known.
  void apply(const YAML::Node& map, const std::string& prefix) const {
    if (!map.IsMap()) fail(origin_, (prefix.empty() ? "the file" : prefix) + " must be a mapping");
    std::set<std::string> seen;
    for (const auto& item : map) {
      // A key that is a list or a mapping ({[a]: 1}) names no setting.
      if (!item.first.IsScalar()) {
        fail(origin_, (prefix.empty() ? "the file" : prefix) + " has a key that is not a word");
      }
      const auto name = item.first.Scalar();
      const std::string key = prefix.empty() ? name : prefix + "." + name;
      // YAML would let the last of two equal keys win without a word.
      if (!seen.insert(name).second) fail(origin_, "key " + quote(key) + " is given twice");
      const auto it = setters_.find(key);
      if (it == setters_.end()) {
        if (sections_.count(key) != 0) {
          sections_.at(key)(item.second, key);
          continue;
        }
        fail(origin_, "unknown key " + quote(key));
      }
      if (item.second.IsNull()) fail(origin_, key + " has no value");
      it->second(item.second, key);
    }
  }
  void section(const std::string& key) {
    sections_[key] = [this](const YAML::Node& n, const std::string& k) { apply(n, k); };
  }
  // The keys a file may have at its top level.
  std::set<std::string> top_level_keys() const {
    std::set<std::string> keys;
    for (const auto* m : {&setters_, &sections_}) {
      for (const auto& [key, setter] : *m) keys.insert(key.substr(0, key.find('.')));
    }
    return keys;
  }

 private:
  std::string origin_;
  std::map<std::string, Setter> setters_;
  std::map<std::string, Setter> sections_;
};

// Binds every key of the filter's configuration to its field in @p c.
void bind_filter_config(Binder& b, DynamicFilterConfig& c, const std::string& origin) {
  b.custom("preset", [](const YAML::Node&, const std::string&) {});
  // Read by `dispel odom` (parse_odometry_settings), so that one file can configure both.
  b.custom("odometry", [](const YAML::Node&, const std::string&) {});
  SegmentationConfig& s = c.segmentation;
  b.section("segmentation");
  b.number("segmentation.cluster_gap_m", s.cluster_gap_m);
  b.number("segmentation.cluster_gap_spacings", s.cluster_gap_spacings);
  b.integer("segmentation.min_points", s.min_points);
  b.number("segmentation.min_width_m", s.min_width_m);
  b.choice<GapMetric>(
      "segmentation.gap_metric", s.gap_metric,
      {{"euclidean", GapMetric::kEuclidean}, {"range_difference", GapMetric::kRangeDifference}});
  b.boolean("segmentation.merge_facing_edges", s.merge_facing_edges);
  b.boolean("segmentation.join_full_circle_seam", s.join_full_circle_seam);
  // Called by Binder::apply(), after this function has returned: nothing local by reference.
  b.custom("segmentation.masked_sectors",
           [sectors = &s.masked_sectors, origin](const YAML::Node& n, const std::string& k) {
             if (!n.IsSequence()) fail(origin, k + " must be a list of [begin_rad, end_rad] pairs");
             sectors->clear();
             for (std::size_t i = 0; i < n.size(); ++i) {
               const std::string item = k + "[" + std::to_string(i) + "]";
               if (!n[i].IsSequence() || n[i].size() != 2)
                 fail(origin, item + " must be [begin_rad, end_rad]");
               sectors->push_back({scalar<double>(n[i][0], item, origin, "a number"),
                                   scalar<double>(n[i][1], item, origin, "a number")});
             }
           });
  TrackingConfig& t = c.tracking;
  b.section("tracking");
  b.number("tracking.match_distance_m", t.match_distance_m);
  b.choice<Matching>(
      "tracking.matching", t.matching,
      {{"global", Matching::kGlobal}, {"nearest_neighbour", Matching::kNearestNeighbour}});
  b.integer("tracking.max_missed_scans", t.max_missed_scans);
  b.boolean("tracking.inherit_on_split", t.inherit_on_split);
  b.number("tracking.max_gate_m", t.max_gate_m);
  b.number("tracking.max_extent_change_m", t.max_extent_change_m);
  b.number("tracking.companion_distance_m", t.companion_distance_m);
  b.number("tracking.companion_speed_difference_mps", t.companion_speed_difference_mps);
  b.number("tracking.fragment_distance_m", t.fragment_distance_m);
  b.boolean("tracking.follow_fragments", t.follow_fragments);
  b.boolean("tracking.remove_edge_pixels", t.remove_edge_pixels);
  VelocityFilterConfig& v = c.velocity;
  b.section("velocity");
  b.number("velocity.position_variance_m2", v.position_variance_m2);
  b.number("velocity.velocity_variance_m2ps2", v.velocity_variance_m2ps2);
  b.number("velocity.measurement_variance_m2", v.measurement_variance_m2);
  b.number("velocity.velocity_decay", v.velocity_decay);
  b.number("velocity.nominal_scan_period_s", v.nominal_scan_period_s);
  ClassificationConfig& k = c.classification;
  b.section("classification");
  b.choice<Presumption>("classification.presumption", k.presumption,
                        {{"innocence", Presumption::kInnocence}, {"guilt", Presumption::kGuilt}});
  b.number("classification.speed_limit_mps", k.speed_limit_mps);
  b.integer("classification.dynamic_weight_limit", k.dynamic_weight_limit);
  b.integer("classification.static_weight_limit", k.static_weight_limit);
  b.number("classification.max_direction_difference_rad", k.max_direction_difference_rad);
  b.number("classification.max_dynamic_extent_m", k.max_dynamic_extent_m);
  b.number("classification.max_point_count_ratio", k.max_point_count_ratio);
  b.integer("classification.still_scans_to_static", k.still_scans_to_static);
  b.number("classification.still_alone_to_static_s", k.still_alone_to_static_s);
  b.boolean("classification.slow_scans_reduce_dynamic_weight", k.slow_scans_reduce_dynamic_weight);
  FreeSpaceConfig& f = c.free_space;
  b.section("free_space");
  b.boolean("free_space.enabled", f.enabled);
  b.number("free_space.cell_size_m", f.cell_size_m);
  b.number("free_space.extent_m", f.extent_m);
  b.number("free_space.margin_m", f.margin_m);
  b.integer("free_space.min_free_observations", f.min_free_observations);
  b.integer("free_space.max_recent_hits", f.max_recent_hits);
  b.number("free_space.free_range_m", f.free_range_m);
  b.boolean("free_space.no_return_is_free", f.no_return_is_free);
  b.number("free_space.memory_s", f.memory_s);
  b.boolean("free_space.keep_long_occupied", f.keep_long_occupied);
  b.integer("free_space.long_occupied_scans", f.long_occupied_scans);
  b.integer("free_space.neighbourhood_cells", f.neighbourhood_cells);
  b.number("free_space.min_object_share", f.min_object_share);
  b.boolean("free_space.mark_beside_dynamic", f.mark_beside_dynamic);
  b.choice<RequireUnseen>("free_space.require_unseen", f.require_unseen,
                          {{"never", RequireUnseen::kNever},
                           {"laser_only", RequireUnseen::kLaserOnly},
                           {"always", RequireUnseen::kAlways}});
  RegistrationConfig& g = c.registration;
  b.section("registration");
  b.boolean("registration.enabled", g.enabled);
  b.boolean("registration.align", g.align);
  b.number("registration.voxel_size_m", g.voxel_size_m);
  b.integer("registration.max_points_per_voxel", g.max_points_per_voxel);
  b.number("registration.scan_spacing_m", g.scan_spacing_m);
  b.number("registration.max_range_m", g.max_range_m);
  b.number("registration.local_map_radius_m", g.local_map_radius_m);
  b.integer("registration.max_iterations", g.max_iterations);
  b.number("registration.initial_threshold_m", g.initial_threshold_m);
  b.number("registration.min_threshold_m", g.min_threshold_m);
  b.number("registration.max_threshold_m", g.max_threshold_m);
  b.number("registration.min_inlier_share", g.min_inlier_share);
  b.integer("registration.min_points", g.min_points);
  b.integer("registration.min_points_with_odometry", g.min_points_with_odometry);
  b.number("registration.max_correction_m", g.max_correction_m);
  b.number("registration.max_correction_rad", g.max_correction_rad);
  b.number("registration.range_noise_m", g.range_noise_m);
  b.number("registration.odometry_noise_m", g.odometry_noise_m);
  b.number("registration.odometry_noise_rad", g.odometry_noise_rad);
  b.number("registration.constant_velocity_noise_m", g.constant_velocity_noise_m);
  b.number("registration.constant_velocity_noise_rad", g.constant_velocity_noise_rad);
  b.number("registration.velocity_smoothing", g.velocity_smoothing);
  b.number("registration.degeneracy_ratio", g.degeneracy_ratio);
  b.integer("registration.explained_min_scans", g.explained_min_scans);
  b.number("registration.explained_min_span_s", g.explained_min_span_s);
  b.number("registration.explained_min_span_in_free_s", g.explained_min_span_in_free_s);
  b.number("registration.explained_distance_m", g.explained_distance_m);
  b.number("registration.explained_max_age_s", g.explained_max_age_s);
  b.number("registration.slide_tolerance_mps", g.slide_tolerance_mps);
  b.boolean("registration.deskew", g.deskew);
  b.boolean("registration.deskew_laser_only_turn", g.deskew_laser_only_turn);
  b.number("registration.lateral_noise_mps", g.lateral_noise_mps);
  b.number("registration.fallback_turn_decay_s", g.fallback_turn_decay_s);
  b.boolean("registration.leave_out_moving", g.leave_out_moving);
  b.number("max_time_gap_s", c.max_time_gap_s);
  b.number("max_pose_jump_m", c.max_pose_jump_m);
  b.number("max_pose_jump_rad", c.max_pose_jump_rad);
  b.number("max_speed_mps", c.max_speed_mps);
  b.number("max_turn_rate_radps", c.max_turn_rate_radps);
}

}  // namespace

DynamicFilterConfig parse_filter_config(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    fail(origin, std::string("not valid YAML: ") + e.what());
  }
  DynamicFilterConfig c;
  if (root.IsNull()) {
    // An empty file: all defaults.
  } else {
    // The starting point, whatever its place in the file: every other key changes it.
    if (root.IsMap() && root["preset"]) {
      const std::string preset = scalar<std::string>(root["preset"], "preset", origin, "a word");
      if (preset == "thesis") {
        c = thesis_config();
      } else if (preset != "default") {
        fail(origin, "preset must be one of default, thesis, got " + quote(preset));
      }
    }
    Binder b(origin);
    bind_filter_config(b, c, origin);
    b.apply(root, "");
  }
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    fail(origin, e.what());
  }
  return c;
}

std::set<std::string> filter_config_top_level_keys() {
  DynamicFilterConfig c;
  Binder b("");
  bind_filter_config(b, c, "");
  return b.top_level_keys();
}

namespace {

std::string read_text(const std::string& path) {
  return read_regular_file(path, "configuration file");
}

}  // namespace

DynamicFilterConfig load_filter_config(const std::string& path) {
  return parse_filter_config(read_text(path), path);
}

OdometrySettings parse_odometry_settings(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    fail(origin, std::string("not valid YAML: ") + e.what());
  }
  OdometrySettings settings;
  if (!root.IsNull() && !root.IsMap()) fail(origin, "the file must be a mapping");
  if (root.IsNull() || !root["odometry"]) return settings;  // The filter's keys are not ours.
  OdometryConfig& c = settings.filter;
  Binder b(origin);
  b.choice<OdometryModel>("odometry.model", c.model,
                          {{"ct", OdometryModel::kCt},
                           {"ct_euler", OdometryModel::kCtEuler},
                           {"omni", OdometryModel::kOmni}});
  b.number("odometry.track_width_m", c.track_width_m);
  b.number("odometry.linear_velocity_variance_m2ps3", c.linear_velocity_variance_m2ps3);
  b.number("odometry.yaw_rate_variance_rad2ps3", c.yaw_rate_variance_rad2ps3);
  b.number("odometry.ukf_alpha", c.ukf_alpha);
  b.number("odometry.ukf_beta", c.ukf_beta);
  b.number("odometry.ukf_kappa", c.ukf_kappa);
  b.number("odometry.wheel_velocity_variance_m2ps2", c.wheel_velocity_variance_m2ps2);
  b.number("odometry.wheel_yaw_rate_variance_rad2ps2", c.wheel_yaw_rate_variance_rad2ps2);
  b.number("odometry.wheel_lateral_velocity_variance_m2ps2",
           c.wheel_lateral_velocity_variance_m2ps2);
  b.number("odometry.imu_yaw_rate_variance_rad2ps2", c.imu_yaw_rate_variance_rad2ps2);
  b.number("odometry.imu_smoothing", c.imu_smoothing);
  b.boolean("odometry.gyro_bias_enabled", c.gyro_bias_enabled);
  b.number("odometry.gyro_bias_initial_variance_rad2ps2", c.gyro_bias_initial_variance_rad2ps2);
  b.number("odometry.gyro_bias_random_walk_variance_rad2ps3",
           c.gyro_bias_random_walk_variance_rad2ps3);
  b.number("odometry.gate_probability", c.gate_probability);
  b.number("odometry.gate_override_after_s", c.gate_override_after_s);
  b.number("odometry.gate_agreement_radps", c.gate_agreement_radps);
  b.number("odometry.gate_agreement_window_s", c.gate_agreement_window_s);
  b.boolean("odometry.gate_wheels_without_imu", c.gate_wheels_without_imu);
  b.number("odometry.max_time_step_s", c.max_time_step_s);
  b.number("odometry.initial_position_variance_m2", c.initial_position_variance_m2);
  b.number("odometry.initial_yaw_variance_rad2", c.initial_yaw_variance_rad2);
  b.number("odometry.initial_velocity_variance_m2ps2", c.initial_velocity_variance_m2ps2);
  b.number("odometry.initial_yaw_rate_variance_rad2ps2", c.initial_yaw_rate_variance_rad2ps2);
  b.number("odometry.wheel_radius_m", settings.wheel_radius_m);
  b.custom("odometry.left_wheel_joint", [&](const YAML::Node& n, const std::string& k) {
    settings.left_wheel_joint = scalar<std::string>(n, k, origin, "a joint name");
  });
  b.custom("odometry.right_wheel_joint", [&](const YAML::Node& n, const std::string& k) {
    settings.right_wheel_joint = scalar<std::string>(n, k, origin, "a joint name");
  });
  b.custom("odometry.imu_yaw_axis", [&](const YAML::Node& n, const std::string& k) {
    const auto axis = scalar<std::string>(n, k, origin, "an axis");
    const std::map<std::string, std::pair<int, double>> axes{{"x", {0, 1.0}}, {"-x", {0, -1.0}},
                                                             {"y", {1, 1.0}}, {"-y", {1, -1.0}},
                                                             {"z", {2, 1.0}}, {"-z", {2, -1.0}}};
    const auto it = axes.find(axis);
    if (it == axes.end())
      fail(origin, k + " must be one of x, -x, y, -y, z, -z, got " + quote(axis));
    settings.imu_yaw_axis = it->second.first;
    settings.imu_yaw_sign = it->second.second;
  });
  b.section("odometry");
  b.apply(root["odometry"], "odometry");
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    fail(origin, e.what());
  }
  if (!(settings.wheel_radius_m >= 0.0 && std::isfinite(settings.wheel_radius_m))) {
    fail(origin, "odometry.wheel_radius_m must be a finite number >= 0, got " +
                     std::to_string(settings.wheel_radius_m));
  }
  return settings;
}

OdometrySettings load_odometry_settings(const std::string& path) {
  return parse_odometry_settings(read_text(path), path);
}

}  // namespace dispel::io
