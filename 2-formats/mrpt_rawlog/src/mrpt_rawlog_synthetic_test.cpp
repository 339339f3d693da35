// Rawlogs written here with MRPT itself, for what Debian's wheelchair log does not hold: labelled
// lasers scanning left to right, absolute odometry observations, actions without time stamps, a
// mount that changes, and observations of other classes.
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/math/CMatrixB.h>
#include <mrpt/math/CMatrixD.h>
#include <mrpt/math/CMatrixF.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>

#include "dispel/io/errors.hpp"
#include "dispel/io/mrpt_rawlog.hpp"
#include "test_files.hpp"

namespace dispel::io {
namespace {

using test::temp_path;

constexpr double kPi = 3.14159265358979323846;
constexpr double kT0 = 1700000000.25;  // Seconds since the Unix epoch.

mrpt::obs::CObservation2DRangeScan::Ptr laser(const std::string& label, double t,
                                              bool right_to_left, double mount_x) {
  auto s = mrpt::obs::CObservation2DRangeScan::Create();
  s->sensorLabel = label;
  s->timestamp = mrpt::Clock::fromDouble(t);
  s->aperture = static_cast<float>(kPi);
  s->rightToLeft = right_to_left;
  s->maxRange = 30.0F;
  s->sensorPose = mrpt::poses::CPose3D(mount_x, 0.1, 0.2, 0.5, 0.0, 0.0);
  s->resizeScan(5);
  for (std::size_t k = 0; k < 5; ++k) {
    s->setScanRange(k, 1.0F + static_cast<float>(k));  // Beam k at 1 + k metres.
    s->setScanRangeValidity(k, k != 1);
  }
  return s;
}

std::map<std::string, std::vector<std::pair<Stamp, std::string>>> read_all(
    MrptRawlogReader& reader, std::vector<ScanMessage>* scans = nullptr,
    std::vector<OdometryMessage>* odometry = nullptr,
    std::vector<TransformsMessage>* mounts = nullptr) {
  std::map<std::string, std::vector<std::pair<Stamp, std::string>>> seen;
  reader.read({}, [&](const RecordedMessage& m) {
    seen[m.topic()].emplace_back(m.time(), message_kind_name(m.kind()));
    if (auto s = m.scan(); s && scans) scans->push_back(*s);
    if (auto o = m.odometry(); o && odometry) odometry->push_back(*o);
    if (auto t = m.transforms(); t && mounts) mounts->push_back(*t);
  });
  return seen;
}

// The error opening the log at @p path gives, or "read".
std::string open_error(const std::string& path) {
  try {
    MrptRawlogReader reader(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "read";
}

// @p bytes with the action object whose class name is at @p at made MRPT's abstract
// "mrpt::obs::CAction" (NUL-padded to the same length: MRPT takes the name as a C string) with
// no fields: the byte after its version ends it.
std::string abstract_action_at(std::string bytes, std::size_t at) {
  const std::size_t length = std::string("mrpt::obs::CActionRobotMovement2D").size();
  bytes.replace(at, length, std::string("mrpt::obs::CAction") + std::string(15, '\0'));
  bytes[at + length + 1] = '\x88';
  return bytes;
}

// Observations only (the newer format): two lasers, absolute odometry, a comment, all in one
// gzip-compressed file, the second laser's observations given out of time order.
TEST(MrptRawlogSynthetic, ObservationsFormatWithLabelledLeftToRightLasers) {
  const std::string path = temp_path("observations.rawlog");
  {
    mrpt::io::CFileGZOutputStream out(path);
    auto archive = mrpt::serialization::archiveFrom(out);
    auto comment = mrpt::obs::CObservationComment::Create();
    comment->timestamp = mrpt::Clock::fromDouble(kT0);
    comment->text = "a comment";
    archive << *comment;
    for (int k = 0; k < 3; ++k) {
      auto odom = mrpt::obs::CObservationOdometry::Create();
      odom->timestamp = mrpt::Clock::fromDouble(kT0 + 0.1 * k);
      odom->odometry = mrpt::poses::CPose2D(0.5 * k, 0.0, 0.1 * k);
      odom->hasVelocities = true;
      odom->velocityLocal = mrpt::math::TTwist2D(5.0, 0.0, 1.0);
      archive << *odom;
      // The mount of the front laser moves once, at k = 2.
      archive << *laser("LASER front.1", kT0 + 0.1 * k + 0.05, false, k < 2 ? 0.3 : 0.4);
    }
    archive << *laser("", kT0 + 0.02, true, 0.0);  // Earlier than the messages before it.
  }
  MrptRawlogReader reader(path);
  std::vector<ScanMessage> scans;
  std::vector<OdometryMessage> odometry;
  std::vector<TransformsMessage> mounts;
  const auto seen = read_all(reader, &scans, &odometry, &mounts);
  EXPECT_EQ(reader.skipped_count(), 1);
  EXPECT_EQ(reader.skipped().at("mrpt::obs::CObservationComment"), 1);
  ASSERT_EQ(seen.size(), 4u);
  EXPECT_EQ(seen.at("/LASER_front_1").size(), 3u);
  EXPECT_EQ(seen.at("/scan").size(), 1u);
  EXPECT_EQ(seen.at("/odom").size(), 3u);
  EXPECT_EQ(seen.at("/tf_static").size(), 3u);  // Each laser's first mount, and the change.
  EXPECT_EQ(reader.topics().all().at("/LASER_front_1").type, "sensor_msgs/LaserScan");
  EXPECT_NEAR(reader.begin_time().seconds(), kT0, 1e-6);
  EXPECT_NEAR(reader.end_time().seconds(), kT0 + 0.25, 1e-6);

  ASSERT_EQ(scans.size(), 4u);
  EXPECT_EQ(scans[0].header.frame_id, "laser");  // The unlabelled one, by its stamp.
  EXPECT_NEAR(scans[0].scan.stamp_s, kT0 + 0.02, 1e-6);
  const ScanMessage& front = scans[1];
  EXPECT_EQ(front.header.frame_id, "LASER_front_1");
  EXPECT_NEAR(front.scan.angle_min_rad, -kPi / 2, 1e-6);
  EXPECT_NEAR(front.scan.angle_increment_rad, kPi / 4, 1e-6);
  EXPECT_EQ(front.scan.range_max_m, 30.0F);
  // Left to right: MRPT's beam 0 is at +90°, our last beam; MRPT's beam 1 (invalid) our beam 3.
  EXPECT_EQ(front.scan.ranges_m[4], 1.0F);
  EXPECT_TRUE(std::isnan(front.scan.ranges_m[3]));
  EXPECT_EQ(front.scan.ranges_m[0], 5.0F);
  // Right to left: as MRPT has them.
  EXPECT_EQ(scans[0].scan.ranges_m[0], 1.0F);
  EXPECT_TRUE(std::isnan(scans[0].scan.ranges_m[1]));

  ASSERT_EQ(odometry.size(), 3u);
  EXPECT_EQ(odometry[2].pose.x_m, 1.0);
  EXPECT_NEAR(odometry[2].pose.yaw_rad, 0.2, 1e-12);
  EXPECT_EQ(odometry[2].v_mps, 5.0);
  EXPECT_EQ(odometry[2].w_radps, 1.0);

  ASSERT_EQ(mounts.size(), 3u);
  EXPECT_EQ(mounts[0].transforms[0].child, "laser");
  EXPECT_EQ(mounts[1].transforms[0].child, "LASER_front_1");
  EXPECT_NEAR(mounts[1].transforms[0].child_in_parent.x_m, 0.3, 1e-6);
  EXPECT_NEAR(mounts[1].transforms[0].child_in_parent.y_m, 0.1, 1e-6);
  EXPECT_NEAR(mounts[1].transforms[0].child_in_parent.yaw_rad, 0.5, 1e-6);
  EXPECT_NEAR(mounts[2].transforms[0].child_in_parent.x_m, 0.4, 1e-6);
  EXPECT_NEAR(mounts[2].transforms[0].stamp.seconds(), kT0 + 0.25, 1e-6);
}

// Actions and sensory frames without time stamps on the actions: each integrated pose is stamped
// with the next sensory frame's earliest observation, the last one with the last stamp seen.
// An action is the motion from one sensory frame to the next (MRPT's convention): the pose it
// leads to is stated at the next frame's stamp, not at the action's own (MRPT's grabber stamps it
// half-way); an action with no frame after it at its own stamp, or the last one seen.
TEST(MrptRawlogSynthetic, AnActionsPoseIsStatedAtTheNextSensoryFrame) {
  const std::string path = temp_path("actions.rawlog");
  {
    mrpt::io::CFileOutputStream out(path);  // Uncompressed.
    auto archive = mrpt::serialization::archiveFrom(out);
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions model;
    for (int k = 0; k < 3; ++k) {
      mrpt::obs::CSensoryFrame frame;
      frame.insert(laser("front", kT0 + k, true, 0.3));
      archive << frame;
      mrpt::obs::CActionRobotMovement2D move;
      move.computeFromOdometry(mrpt::poses::CPose2D(1.0, 0.0, kPi / 2), model);
      if (k != 1) move.timestamp = mrpt::Clock::fromDouble(kT0 + k + 0.5);  // Half-way.
      mrpt::obs::CActionCollection actions;
      actions.insert(move);
      archive << actions;
    }
  }
  MrptRawlogReader reader(path);
  std::vector<OdometryMessage> odometry;
  const auto seen = read_all(reader, nullptr, &odometry);
  EXPECT_EQ(seen.at("/front").size(), 3u);
  ASSERT_EQ(odometry.size(), 4u);  // The identity at the first scan, and one per action.
  EXPECT_EQ(odometry[0].pose.x_m, 0.0);
  EXPECT_NEAR(odometry[0].header.stamp.seconds(), kT0, 1e-6);
  // One metre forward then a quarter turn left, three times.
  EXPECT_NEAR(odometry[1].pose.x_m, 1.0, 1e-9);
  EXPECT_NEAR(odometry[2].pose.x_m, 1.0, 1e-9);
  EXPECT_NEAR(odometry[2].pose.y_m, 1.0, 1e-9);
  EXPECT_NEAR(odometry[3].pose.x_m, 0.0, 1e-9);
  EXPECT_NEAR(odometry[3].pose.y_m, 1.0, 1e-9);
  EXPECT_NEAR(std::remainder(odometry[3].pose.yaw_rad + kPi / 2, 2 * kPi), 0.0, 1e-9);
  EXPECT_NEAR(odometry[1].header.stamp.seconds(), kT0 + 1, 1e-6);
  EXPECT_NEAR(odometry[2].header.stamp.seconds(), kT0 + 2, 1e-6);
  EXPECT_NEAR(odometry[3].header.stamp.seconds(), kT0 + 2.5, 1e-6);  // No frame after it.
}

// MRPT 2 stores the full class name (mrpt::obs::CSensoryFrame): the top-level container check
// knows it too. A sensory frame of one scan, its count then set to 2^32 - 1.
TEST(MrptRawlogSynthetic, ContainerCountCheckedUnderMrpt2sFullClassName) {
  const std::string path = temp_path("full_name.rawlog");
  {
    mrpt::io::CFileOutputStream out(path);
    auto archive = mrpt::serialization::archiveFrom(out);
    mrpt::obs::CSensoryFrame frame;
    frame.insert(laser("", kT0, true, 0.0));
    archive << frame;
  }
  std::string bytes = test::read_bytes(path);
  const std::string header = "\x98mrpt::obs::CSensoryFrame\x02";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  ASSERT_NO_THROW(MrptRawlogReader{path});
  bytes.replace(header.size(), 4, "\xff\xff\xff\xff");
  test::write_text("full_name.rawlog", bytes);
  EXPECT_EQ(open_error(path),
            path +
                ": not a readable MRPT rawlog (a CSensoryFrame of 4294967295 observations in the " +
                std::to_string(bytes.size() - header.size() - 4) + " bytes left)");
}

// MRPT reads a CActionCollection's actions into pointers it copies through: an action it cannot
// make (the fuzzer stored MRPT's abstract CAction: MRPT makes nothing and gets a null pointer) is
// a SIGSEGV inside MRPT. A frame, then a collection of two odometry actions, read; then the
// second action's class made "mrpt::obs::CAction" (NUL-padded to the same length: MRPT takes the
// name as a C string) with no fields, then the first's.
TEST(MrptRawlogSynthetic, ActionsMrptCannotMakeAreRefused) {
  const std::string path = temp_path("abstract_action.rawlog");
  {
    mrpt::io::CFileOutputStream out(path);
    auto archive = mrpt::serialization::archiveFrom(out);
    mrpt::obs::CSensoryFrame frame;
    frame.insert(laser("front", kT0, true, 0.3));
    archive << frame;
    mrpt::obs::CActionRobotMovement2D move;
    move.computeFromOdometry(mrpt::poses::CPose2D(1.0, 0.0, 0.0),
                             mrpt::obs::CActionRobotMovement2D::TMotionModelOptions{});
    mrpt::obs::CActionCollection actions;
    actions.insert(move);
    actions.insert(move);
    archive << actions;
  }
  const std::string bytes = test::read_bytes(path);
  {
    MrptRawlogReader reader(path);
    std::vector<OdometryMessage> odometry;
    read_all(reader, nullptr, &odometry);
    ASSERT_EQ(odometry.size(), 3u);  // The identity at the scan, then one per action.
    EXPECT_NEAR(odometry[1].pose.x_m, 1.0, 1e-9);
    EXPECT_NEAR(odometry[2].pose.x_m, 2.0, 1e-9);
  }
  const std::string name = "mrpt::obs::CActionRobotMovement2D";
  const std::size_t first = bytes.find(name);
  const std::size_t second = bytes.find(name, first + 1);
  ASSERT_NE(second, std::string::npos);
  for (const auto& [at, k] : {std::pair{second, 1}, std::pair{first, 0}}) {
    const std::string changed = test::write_text("abstract_" + std::to_string(k) + ".rawlog",
                                                 abstract_action_at(bytes, at));
    EXPECT_EQ(open_error(changed),
              changed +
                  ": not a readable MRPT rawlog (truncated or corrupt after 1 objects: action " +
                  std::to_string(k) +
                  " of a CActionCollection is 'CAction', not an action MRPT can "
                  "make)");
  }
}

// A whole CRawlog saved as one object: its entries are read as the log's own (the collection in
// it checked as at the top level), CRawlogs inside each other too, at most 8 deep.
TEST(MrptRawlogSynthetic, AWholeCRawlogIsReadAsTheLogsOwnEntries) {
  mrpt::obs::CRawlog log;
  mrpt::obs::CSensoryFrame frame;
  frame.insert(laser("front", kT0, true, 0.3));
  log.insert(frame);
  mrpt::obs::CActionRobotMovement2D move;
  move.computeFromOdometry(mrpt::poses::CPose2D(1.0, 0.0, 0.0),
                           mrpt::obs::CActionRobotMovement2D::TMotionModelOptions{});
  mrpt::obs::CActionCollection actions;
  actions.insert(move);
  actions.insert(move);
  log.insert(actions);
  log.setCommentText("a comment");
  const auto nested = [&](int depth) {  // @p log inside depth - 1 others.
    auto outer = std::make_shared<mrpt::obs::CRawlog>(log);
    for (int d = 1; d < depth; ++d) {
      auto next = std::make_shared<mrpt::obs::CRawlog>();
      next->insert(outer);
      outer = next;
    }
    const std::string path = temp_path("whole_" + std::to_string(depth) + ".rawlog");
    mrpt::io::CFileOutputStream out(path);
    mrpt::serialization::archiveFrom(out) << *outer;
    return path;
  };
  for (const int depth : {1, 8}) {
    MrptRawlogReader reader(nested(depth));
    std::vector<OdometryMessage> odometry;
    const auto seen = read_all(reader, nullptr, &odometry);
    EXPECT_EQ(seen.at("/front").size(), 1u) << depth;
    ASSERT_EQ(odometry.size(), 3u) << depth;
    EXPECT_NEAR(odometry[2].pose.x_m, 2.0, 1e-9) << depth;
  }
  const std::string deep = nested(9);
  EXPECT_EQ(open_error(deep),
            deep + ": not a readable MRPT rawlog (CRawlogs nested more than 8 deep)");
  const std::string bytes = test::read_bytes(nested(1));
  const std::string name = "mrpt::obs::CActionRobotMovement2D";
  const std::size_t second = bytes.find(name, bytes.find(name) + 1);
  ASSERT_NE(second, std::string::npos);
  const std::string abstract =
      test::write_text("whole_abstract.rawlog", abstract_action_at(bytes, second));
  EXPECT_EQ(open_error(abstract),
            abstract +
                ": not a readable MRPT rawlog (action 1 of a CActionCollection is 'CAction', not "
                "an action MRPT can make)");
}

// MRPT makes a matrix's storage before it reads its values and writes through the null pointer it
// gets when the allocation fails (SIGSEGV). Each matrix class MRPT 2 reads, written by MRPT as a
// top-level object, its size then stated as 4294963200 x 1024: refused before MRPT reads it,
// under MRPT 2's name and under every stored name MRPT reads as the same class (it takes the name
// up to its first NUL and, when that is not a registered full name, the part after its last
// "::"): the short name, MRPT 1's "CMatrix" for a CMatrixF, and any bytes ending in "::" before
// either, each NUL-padded to the 20 bytes of the name MRPT wrote, as the fuzzer stored them.
TEST(MrptRawlogSynthetic, MatricesOfEveryClassMrptReadsAreCheckedBeforeItReadsThem) {
  const auto written = [](const std::string& file, const auto& matrix) {
    const std::string path = temp_path(file);
    {
      mrpt::io::CFileOutputStream out(path);
      mrpt::serialization::archiveFrom(out) << matrix;
    }
    return test::read_bytes(path);
  };
  struct Case {
    std::string bytes;
    std::string name;               // As MRPT 2 stores it.
    std::size_t rows_after;         // Bytes between the version and the rows.
    std::vector<std::string> also;  // Other stored names of the class (up to 20 bytes).
  };
  const std::vector<Case> cases = {{written("d.rawlog", mrpt::math::CMatrixD(2, 3)),
                                    "mrpt::math::CMatrixD",
                                    0,
                                    {"CMatrixD", "x\xff::y::CMatrixD"}},
                                   {written("f.rawlog", mrpt::math::CMatrixF(2, 3)),
                                    "mrpt::math::CMatrixF",
                                    0,
                                    {"CMatrix", "\x01\x02::CMatrix", "mrpt::math::CMatrix"}},
                                   {written("b.rawlog", mrpt::math::CMatrixB(2, 3)),
                                    "mrpt::math::CMatrixB",
                                    4,
                                    {"q::CMatrixB"}}};
  for (const Case& c : cases) {
    const std::string header = std::string(1, static_cast<char>(0x80 | c.name.size())) + c.name;
    ASSERT_EQ(c.bytes.substr(0, header.size()), header);
    const std::size_t rows_at = header.size() + 1 + c.rows_after;
    ASSERT_EQ(c.bytes.substr(rows_at, 8), std::string("\x02\x00\x00\x00\x03\x00\x00\x00", 8));
    const std::string shown = c.name.substr(12);
    EXPECT_EQ(open_error(test::write_text("fine_" + shown + ".rawlog", c.bytes)), "read");
    std::vector<std::string> named = {c.bytes};
    for (const std::string& name : c.also) {
      ASSERT_LE(name.size(), c.name.size());
      named.push_back(c.bytes);
      named.back().replace(1, c.name.size(), name + std::string(c.name.size() - name.size(), '\0'));
    }
    for (std::size_t k = 0; k < named.size(); ++k) {
      std::string& bytes = named[k];
      bytes.replace(rows_at, 8, std::string("\x00\xf0\xff\xff\x00\x04\x00\x00", 8));
      const std::string path =
          test::write_text("huge_" + shown + "_" + std::to_string(k) + ".rawlog", bytes);
      EXPECT_EQ(open_error(path), path + ": not a readable MRPT rawlog (a " + shown +
                                      " of 4294963200 x 1024 values at byte 0, more than the " +
                                      std::to_string(bytes.size() - rows_at - 8) +
                                      " bytes after it)")
          << (k == 0 ? c.name : c.also[k - 1]);
    }
  }
}

}  // namespace
}  // namespace dispel::io
