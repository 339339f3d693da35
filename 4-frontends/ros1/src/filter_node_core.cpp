#include "dispel/ros1/filter_node_core.hpp"

#include "dispel/io/ros1_messages.hpp"

namespace dispel::ros1 {

FilterNodeCore::Output FilterNodeCore::process(const sensor_msgs::LaserScan& msg, double stamp_s,
                                               const std::optional<Pose2>& sensor_pose) {
  const io::ScanMessage scan = io::to_message(msg);
  LaserScan core = scan.scan;
  if (msg.header.stamp.isZero()) core.stamp_s = stamp_s;
  const FilterResult& result = runner_.process(core, scan.scan_time, sensor_pose);
  return {io::to_ros(io::filtered_message(scan, result)),
          io::to_ros(io::labels_message(scan, result)), &result};
}

}  // namespace dispel::ros1
