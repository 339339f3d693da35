#include "dispel/ros1/filter_node_core.hpp"

#include "dispel/io/ros1_messages.hpp"

namespace dispel::ros1 {

FilterNodeCore::Output FilterNodeCore::process(const sensor_msgs::LaserScan& msg, double stamp_s,
                                               const std::optional<Pose2>& sensor_pose) {
  io::ScanMessage scan = io::to_message(msg);
  // The filter's time; the published header keeps the message's own stamp.
  if (msg.header.stamp.isZero()) scan.scan.stamp_s = stamp_s;
  const FilterResult& result = runner_.process(scan.scan, scan.scan_time, sensor_pose);
  return {io::to_ros(io::filtered_message(scan, result)),
          io::to_ros(io::labels_message(scan, result)), &result};
}

}  // namespace dispel::ros1
