#pragma once
/// @file
/// MRPT rawlogs (.rawlog, plain or gzip-compressed), read with MRPT's own deserialisation, as a
/// RecordingReader of recording.hpp. MRPT's headers stay in the .cpp; its errors come out as
/// InputError naming the file.
///
/// What a rawlog becomes:
/// - every mrpt::obs::CObservation2DRangeScan: a sensor_msgs/LaserScan on "/" + its sensorLabel
///   (characters other than letters, digits and '_' replaced by '_'; "/scan" when the label is
///   empty), in the frame of the same name ("laser" when the label is empty). Beams in MRPT's
///   convention: beam k of N at -aperture/2 + k * aperture/(N-1) when rightToLeft, mirrored
///   otherwise (then the beams are reversed, so the increment is always positive); a beam whose
///   validity flag is false is NaN (an invalid beam of the core); range_min 0, range_max the
///   scan's maxRange.
/// - the laser's sensorPose (x, y, yaw of the CPose3D): a tf2_msgs/TFMessage on "/tf_static",
///   base_link -> the scan's frame, just before that frame's first scan and again whenever it
///   changes.
/// - odometry: nav_msgs/Odometry on "/odom" (odom -> base_link). In the actions/observations
///   format each CActionRobotMovement2D's increment (the mean of its poseChange) is integrated
///   from the identity. An action is the motion from one sensory frame to the next (MRPT's
///   convention), so the pose it leads to is stamped with the next sensory frame's stamp (its
///   earliest observation's); an action with no frame after it, with its own stamp or the last
///   one seen. A pose at the identity is stated at the first observation's stamp when it comes
///   before the first action. A CObservationOdometry gives its absolute pose as it is.
/// - every other observation or action is skipped and counted (skipped()).
///
/// Stamps are MRPT's (100 ns since 1601, mrpt::Clock) as seconds since the Unix epoch; a message's
/// receive time is its stamp.
///
/// The whole log is read and decoded when it is opened and held in memory, as the recording
/// model's messages: about 1.6 kB per scan of 361 beams (4 bytes a range plus the message's
/// fields), a few hundred bytes per odometry or mount message. MRPT's own objects are not kept.

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "dispel/io/recording.hpp"

namespace dispel::io {

class MrptRawlogReader final : public RecordingReader {
 public:
  /// Opens and reads @p path. @throws InputError "<path>: cannot open (...)" when it cannot be
  /// opened, "<path>: not a readable MRPT rawlog (...)" when it is not a rawlog, holds no MRPT
  /// object, or is truncated or corrupt (a gzip-compressed log whose size disagrees with its
  /// trailer is truncated, even when it ends between two objects).
  explicit MrptRawlogReader(const std::string& path);
  ~MrptRawlogReader() override;

  const std::string& path() const override;
  std::string format_name() const override { return "MRPT rawlog"; }
  const Topics& topics() const override;
  Stamp begin_time() const override;
  Stamp end_time() const override;
  /// Never fails: the log was read when it was opened.
  void read(const std::vector<std::string>& topics,
            const std::function<void(const RecordedMessage&)>& visit) override;

  /// The observations and actions of other classes, skipped, by MRPT class name.
  const std::map<std::string, std::int64_t>& skipped() const;
  /// Their number.
  std::int64_t skipped_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dispel::io
