#include "dispel/ros1/convert.hpp"

#include <algorithm>
#include <cmath>

#include "dispel/io/ros1_messages.hpp"

namespace dispel::ros1 {
namespace {

std_msgs::ColorRGBA colour_of(ObjectClass c) {
  std_msgs::ColorRGBA colour;
  colour.a = 0.8F;
  switch (c) {
    case ObjectClass::kDynamic:
      colour.r = 0.9F;
      colour.g = 0.1F;
      colour.b = 0.1F;
      break;
    case ObjectClass::kUnknown:
      colour.r = 1.0F;
      colour.g = 0.6F;
      colour.b = 0.0F;
      break;
    case ObjectClass::kStatic:
      colour.r = 0.6F;
      colour.g = 0.6F;
      colour.b = 0.6F;
      break;
  }
  return colour;
}

geometry_msgs::Point point(const Eigen::Vector2d& p) {
  geometry_msgs::Point out;
  out.x = p.x();
  out.y = p.y();
  return out;
}

}  // namespace

visualization_msgs::MarkerArray object_markers(const std::vector<TrackedObject>& tracks,
                                               const std_msgs::Header& header) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker clear;
  clear.header = header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  out.markers.push_back(clear);
  for (const TrackedObject& t : tracks) {
    if (t.missed_scans > 0) continue;  // Remembered, not seen now.
    const auto id = static_cast<std::int32_t>(t.id % 0x7fffffff);
    visualization_msgs::Marker m;
    m.header = header;
    m.id = id;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.color = colour_of(t.object_class);

    visualization_msgs::Marker body = m;
    body.ns = "objects";
    body.type = visualization_msgs::Marker::CYLINDER;
    body.pose.position = point(t.position_m);
    const double extent = (t.last_edge_m - t.first_edge_m).norm();
    body.scale.x = body.scale.y = std::max(0.1, extent);
    body.scale.z = 0.05;
    out.markers.push_back(body);

    visualization_msgs::Marker outline = m;
    outline.ns = "outlines";
    outline.type = visualization_msgs::Marker::LINE_STRIP;
    outline.scale.x = 0.03;
    outline.points = {point(t.first_edge_m), point(t.position_m), point(t.last_edge_m)};
    out.markers.push_back(outline);

    if (t.velocity_mps.norm() > 1e-3) {
      visualization_msgs::Marker arrow = m;
      arrow.ns = "velocities";
      arrow.type = visualization_msgs::Marker::ARROW;
      arrow.scale.x = 0.03;  // Shaft diameter.
      arrow.scale.y = 0.08;  // Head diameter.
      arrow.scale.z = 0.1;   // Head length.
      arrow.points = {point(t.position_m), point(t.position_m + t.velocity_mps)};
      out.markers.push_back(arrow);
    }

    visualization_msgs::Marker label = m;
    label.ns = "ids";
    label.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    label.pose.position = point(t.position_m);
    label.pose.position.z = 0.3;
    label.scale.z = 0.15;
    label.color.r = label.color.g = label.color.b = label.color.a = 1.0F;
    label.text = std::to_string(t.id);
    out.markers.push_back(label);
  }
  return out;
}

nav_msgs::Odometry odometry_message(const OdometryEstimate& e, const std::string& frame_id,
                                    const std::string& child_frame_id) {
  return io::to_ros(io::odometry_message(e, frame_id, child_frame_id));
}

geometry_msgs::TransformStamped odometry_transform(const OdometryEstimate& e,
                                                   const std::string& frame_id,
                                                   const std::string& child_frame_id) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = io::to_ros_time(e.t_s);
  t.header.frame_id = frame_id;
  t.child_frame_id = child_frame_id;
  t.transform.translation.x = e.x_m;
  t.transform.translation.y = e.y_m;
  t.transform.rotation = io::quaternion_from_yaw(e.yaw_rad);
  return t;
}

diagnostic_msgs::DiagnosticStatus to_ros(const pipeline::DiagnosticStatus& status) {
  diagnostic_msgs::DiagnosticStatus s;
  s.name = status.name;
  s.level = static_cast<std::uint8_t>(status.level);
  s.message = status.message;
  s.hardware_id = status.hardware_id;
  for (const auto& [key, value] : status.values) {
    diagnostic_msgs::KeyValue kv;
    kv.key = key;
    kv.value = value;
    s.values.push_back(kv);
  }
  return s;
}

}  // namespace dispel::ros1
