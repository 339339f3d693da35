#include "dispel/render/render.hpp"

#include <cairo.h>
#include <fontconfig/fontconfig.h>
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
#include <sstream>

#include "dispel/core/dynamic_filter.hpp"
#include "dispel/core/segmentation.hpp"
#include "dispel/io/ros1_messages.hpp"
#include "dispel/jobs/filter_job.hpp"
#include "dispel/sim/raycast.hpp"
#include "test_files.hpp"

namespace dispel::render {
namespace {

using namespace dispel::io;  // The formats the tests write and read.
using jobs::FilterJobOptions;
using jobs::JobError;
using jobs::run_filter_job;

constexpr double kDeg = kPi / 180.0;

// Cairo and fontconfig keep their font caches for the life of the process; free them at the end
// so that LeakSanitizer (DISPEL_SANITIZE) reports only our leaks.
class FontCacheCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    cairo_debug_reset_static_data();
    FcFini();
  }
};
const auto* const kFontCacheCleanup =
    ::testing::AddGlobalTestEnvironment(new FontCacheCleanup);  // gtest owns it.

using test::temp_path;  // This test process's own folder: ctest runs the tests at once.

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

// A PNG read back with Cairo.
class Picture {
 public:
  explicit Picture(const std::string& path)
      : surface_(cairo_image_surface_create_from_png(path.c_str())) {}
  ~Picture() { cairo_surface_destroy(surface_); }
  Picture(const Picture&) = delete;
  Picture& operator=(const Picture&) = delete;

  bool ok() const { return cairo_surface_status(surface_) == CAIRO_STATUS_SUCCESS; }
  int width() const { return cairo_image_surface_get_width(surface_); }
  int height() const { return cairo_image_surface_get_height(surface_); }
  Rgb at(int u, int v) const {
    const unsigned char* data = cairo_image_surface_get_data(surface_);
    const int stride = cairo_image_surface_get_stride(surface_);
    std::uint32_t px = 0;
    std::memcpy(&px, data + static_cast<std::ptrdiff_t>(v) * stride + 4 * u, 4);
    return {static_cast<std::uint8_t>(px >> 16), static_cast<std::uint8_t>(px >> 8),
            static_cast<std::uint8_t>(px)};
  }
  // The pixel holding the point at image coordinates @p p.
  Rgb at(const Eigen::Vector2d& p) const {
    return at(static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())));
  }
  // Whether a pixel within @p radius pixels of @p p has exactly the colour @p c.
  bool near(const Eigen::Vector2d& p, Rgb c, int radius = 1) const {
    const int u = static_cast<int>(std::floor(p.x())), v = static_cast<int>(std::floor(p.y()));
    for (int dv = -radius; dv <= radius; ++dv) {
      for (int du = -radius; du <= radius; ++du) {
        if (at(u + du, v + dv) == c) return true;
      }
    }
    return false;
  }

 private:
  cairo_surface_t* surface_;
};

std::string describe(Rgb c) {
  std::ostringstream s;
  s << "(" << int{c.r} << ", " << int{c.g} << ", " << int{c.b} << ")";
  return s.str();
}

// --- Scenes ------------------------------------------------------------------------------------

// A 20 x 12 m hall with a pillar at (12, 3) and a person standing at (3, -2).
sim::World hall() {
  sim::World w;
  w.segments = {{{-5, -6}, {15, -6}}, {{15, -6}, {15, 6}}, {{15, 6}, {-5, 6}}, {{-5, 6}, {-5, -6}}};
  w.circles = {{{12.0, 3.0}, 0.3}, {{3.0, -2.0}, 0.25}};
  return w;
}
constexpr std::int32_t kPersonShape = 5;  // 4 segments, then the pillar, then the person.
const Pose2 kMount{0.2, 0.0, 0.1};

struct MapBagOptions {
  bool labels = true;  // Write /scan_labels as dispel filter does: the person's beams label 1.
  bool odometry = true;
  // dispel clean's output instead: /scan_clean and /scan_clean_labels, the person's beams label 5
  // in the first 25 scans and 6 in the last 15, the pillar's 7 (restored, kept).
  bool cleaned = false;
  bool walked_leg = false;  // With cleaned: the person's beams label 8 in every scan instead.
};

// The robot drives along x at 0.5 m/s for 4 s (40 scans at 10 Hz), with odometry on /odom and
// the laser mount on /tf_static. The person's beams are labelled dynamic, the rest static.
std::string write_map_bag(const std::string& name, const MapBagOptions& opt) {
  const std::string path = temp_path(name);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  tf2_msgs::TFMessage tf;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = to_ros_time(100.0);
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "laser";
  mount.transform.translation.x = kMount.x_m;
  mount.transform.rotation = quaternion_from_yaw(kMount.yaw_rad);
  tf.transforms = {mount};
  bag.write("/tf_static", mount.header.stamp, tf);
  const sim::ScanGeometry g{-135.0 * kDeg, 0.25 * kDeg, 1081, 0.05F, 30.0F};
  for (int k = 0; k < 40; ++k) {
    const double t = 100.0 + 0.1 * k;
    const Pose2 base{0.05 * k, 0.0, 0.0};
    if (opt.odometry) {
      bag.write("/odom", to_ros_time(t), to_ros_odometry(t, "odom", "base_link", base, 0.5));
    }
    std::vector<std::int32_t> hit;
    LaserScan scan = sim::raycast(hall(), base * kMount, g, &hit);
    scan.stamp_s = t;
    sensor_msgs::LaserScan msg = to_ros(scan, "laser");
    const std::string topic = opt.cleaned ? "/scan_clean" : "/scan";
    bag.write(topic, msg.header.stamp, msg);
    if (opt.labels) {
      msg.intensities.assign(msg.ranges.size(), 0.0F);
      for (std::size_t i = 0; i < hit.size(); ++i) {
        if (hit[i] == kPersonShape)
          msg.intensities[i] = opt.walked_leg ? 8.0F : opt.cleaned ? (k < 25 ? 5.0F : 6.0F) : 1.0F;
        if (hit[i] == 4 && opt.cleaned) msg.intensities[i] = 7.0F;
        if (hit[i] == sim::kNoHit) msg.intensities[i] = 4.0F;
      }
      bag.write(topic + "_labels", msg.header.stamp, msg);
    }
  }
  return path;
}

// The world point of beam @p i of scan @p k of write_map_bag's robot.
Eigen::Vector2d map_point(int k, std::size_t i, double range) {
  const double b = -135.0 * kDeg + 0.25 * kDeg * static_cast<double>(i);
  return (Pose2{0.05 * k, 0.0, 0.0} * kMount).apply({range * std::cos(b), range * std::sin(b)});
}

// The middle beam of scan @p k that hits shape @p shape, and its range.
std::pair<std::size_t, double> middle_beam_on(int k, std::int32_t shape) {
  std::vector<std::int32_t> hit;
  const sim::ScanGeometry g{-135.0 * kDeg, 0.25 * kDeg, 1081, 0.05F, 30.0F};
  const LaserScan scan = sim::raycast(hall(), Pose2{0.05 * k, 0.0, 0.0} * kMount, g, &hit);
  std::vector<std::size_t> beams;
  for (std::size_t i = 0; i < hit.size(); ++i) {
    if (hit[i] == shape) beams.push_back(i);
  }
  const std::size_t i = beams.at(beams.size() / 2);
  return {i, scan.ranges_m[i]};
}

RenderOptions map_options(const std::string& input, const std::string& output) {
  RenderOptions o;
  o.input = input;
  o.output = output;
  o.width_px = 900;
  o.height_px = 700;
  return o;
}

// --- Map view ----------------------------------------------------------------------------------

TEST(RenderMap, RemovedPointIsDynamicColourWallIsGreyBackgroundElsewhere) {
  const RenderOptions o = map_options(write_map_bag("map.bag", {}), temp_path("map.png"));
  const RenderResult r = render_bag(o);
  EXPECT_TRUE(r.labelled);
  EXPECT_EQ(r.scans_drawn, 40);
  EXPECT_GT(r.points_dynamic, 40 * 10);
  ASSERT_TRUE(exists(o.output));
  EXPECT_FALSE(exists(o.output + ".partial"));

  const Picture pic(o.output);
  ASSERT_TRUE(pic.ok());
  EXPECT_EQ(pic.width(), 900);
  EXPECT_EQ(pic.height(), 700);
  EXPECT_EQ(r.width_px, 900);
  // The person's beams (label 1) of scan 0 and of scan 39.
  for (const int k : {0, 39}) {
    const auto [beam, range] = middle_beam_on(k, kPersonShape);
    const Eigen::Vector2d p = map_point(k, beam, range);
    ASSERT_LT((p - Eigen::Vector2d(3.0, -2.0)).norm(), 0.26);
    EXPECT_EQ(pic.at(r.transform.to_pixel(p)), colours::kDynamic)
        << "scan " << k << ": " << describe(pic.at(r.transform.to_pixel(p)));
  }
  // A pillar beam (label 0): grey to black, never coloured.
  const auto [pillar_beam, pillar_range] = middle_beam_on(20, 4);
  const Rgb pillar = pic.at(r.transform.to_pixel(map_point(20, pillar_beam, pillar_range)));
  EXPECT_TRUE(pillar.r == pillar.g && pillar.g == pillar.b && pillar.r <= colours::kKeptFaint.r)
      << describe(pillar);
  // Empty floor in the middle of the hall, and outside it.
  for (const Eigen::Vector2d& floor : {Eigen::Vector2d(7.0, 3.5), Eigen::Vector2d(9.0, -4.0)}) {
    EXPECT_EQ(pic.at(r.transform.to_pixel(floor)), colours::kBackground);
  }
  // The robot's path along y = 0 from x = 0 to 1.95.
  EXPECT_TRUE(pic.near(r.transform.to_pixel({1.0, 0.0}), colours::kTrajectory, 1));
  // The hall fills the picture: its 20 m width takes most of the 900 pixels.
  const double hall_px = r.transform.scale_px_per_m * 20.0;
  EXPECT_GT(hall_px, 700.0);
  EXPECT_LT(hall_px, 900.0);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

// dispel clean's labels: each removed reason in its colour, a restored point (7) kept.
TEST(RenderMap, CleanedBagDrawsEachReasonForRemovalInItsColour) {
  MapBagOptions b;
  b.cleaned = true;
  RenderOptions o = map_options(write_map_bag("cleaned.bag", b), temp_path("cleaned.png"));
  o.scan_topic = "/scan_clean";
  const RenderResult r = render_bag(o);
  EXPECT_TRUE(r.labelled);
  EXPECT_EQ(r.points_dynamic + r.points_unknown, 0);
  EXPECT_GT(r.points_moved_later, 25 * 10);
  EXPECT_GT(r.points_vacated, 15 * 10);
  const Picture pic(o.output);
  ASSERT_TRUE(pic.ok());
  // The person: moved at another time in 25 scans, seen through in 15; the pixel takes the more
  // frequent reason.
  const auto [beam, range] = middle_beam_on(0, kPersonShape);
  EXPECT_EQ(pic.at(r.transform.to_pixel(map_point(0, beam, range))), colours::kMovedLater);
  // The pillar, restored: grey to black.
  const auto [pillar_beam, pillar_range] = middle_beam_on(20, 4);
  const Rgb pillar = pic.at(r.transform.to_pixel(map_point(20, pillar_beam, pillar_range)));
  EXPECT_TRUE(pillar.r == pillar.g && pillar.g == pillar.b && pillar.r <= colours::kKeptFaint.r)
      << describe(pillar);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());

  // A walked leg in no object (8): its own colour, counted apart.
  b.walked_leg = true;
  o = map_options(write_map_bag("walked_leg.bag", b), temp_path("walked_leg.png"));
  o.scan_topic = "/scan_clean";
  const RenderResult legs = render_bag(o);
  EXPECT_GT(legs.points_walked_legs, 40 * 10);
  EXPECT_EQ(legs.points_moved_later + legs.points_vacated, 0);
  const Picture leg_pic(o.output);
  ASSERT_TRUE(leg_pic.ok());
  EXPECT_EQ(leg_pic.at(legs.transform.to_pixel(map_point(0, beam, range))), colours::kWalkedLeg);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

TEST(RenderMap, UnfilteredBagDrawsEveryPointKept) {
  const RenderOptions o =
      map_options(write_map_bag("unfiltered.bag", {false, true}), temp_path("unfiltered.png"));
  const RenderResult r = render_bag(o);
  EXPECT_FALSE(r.labelled);
  EXPECT_EQ(r.points_dynamic + r.points_unknown, 0);
  const Picture pic(o.output);
  ASSERT_TRUE(pic.ok());
  const auto [beam, range] = middle_beam_on(0, kPersonShape);
  const Rgb c = pic.at(r.transform.to_pixel(map_point(0, beam, range)));
  EXPECT_TRUE(c.r == c.g && c.g == c.b && c.r <= colours::kKeptFaint.r) << describe(c);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

TEST(RenderMap, StaticSensorNeedsNoOdometryAndTimeWindowSelectsScans) {
  RenderOptions o =
      map_options(write_map_bag("no_odom.bag", {true, false}), temp_path("window.png"));
  try {
    render_bag(o);
    ADD_FAILURE() << "rendered without odometry";
  } catch (const JobError& e) {
    EXPECT_NE(std::string(e.what()).find("no nav_msgs/Odometry topic /odom"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(exists(o.output));
  o.static_sensor = true;
  o.from_s = 0.95;  // Scans at 1.0 .. 1.9 s from the start.
  o.to_s = 1.95;
  const RenderResult r = render_bag(o);
  EXPECT_EQ(r.scans_drawn, 10);
  EXPECT_DOUBLE_EQ(r.from_s, 0.95);
  // Identity pose: the person's beam of any scan lands where the laser at the origin sees it.
  const Picture pic(o.output);
  ASSERT_TRUE(pic.ok());
  std::vector<std::int32_t> hit;
  const sim::ScanGeometry g{-135.0 * kDeg, 0.25 * kDeg, 1081, 0.05F, 30.0F};
  const LaserScan scan = sim::raycast(hall(), Pose2{0.5, 0.0, 0.0} * kMount, g, &hit);
  std::size_t beam = 0;
  for (std::size_t i = 0; i < hit.size(); ++i) {
    if (hit[i] == kPersonShape) beam = i;
  }
  const double b = scan.bearing_rad(beam);
  const Eigen::Vector2d p(scan.ranges_m[beam] * std::cos(b), scan.ranges_m[beam] * std::sin(b));
  EXPECT_EQ(pic.at(r.transform.to_pixel(p)), colours::kDynamic);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

TEST(RenderMap, SvgOutputIsAnSvgDocument) {
  const RenderOptions o = map_options(write_map_bag("svg.bag", {}), temp_path("map.svg"));
  render_bag(o);
  std::ifstream in(o.output);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("<svg"), std::string::npos);
  EXPECT_NE(text.str().find("width=\"900"), std::string::npos);
  EXPECT_FALSE(exists(o.output + ".partial"));
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
}

// --- Scan view ---------------------------------------------------------------------------------

// A static scanner at the origin in the hall, the pillar at (3, 1.5), and a person walking from
// (2, -3) along +y at 1 m/s; 10 Hz.
std::string write_scan_bag(const std::string& name) {
  const std::string path = temp_path(name);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const sim::ScanGeometry g{-135.0 * kDeg, 0.25 * kDeg, 1081, 0.05F, 30.0F};
  for (int k = 0; k < 40; ++k) {
    sim::World w = hall();
    w.circles = {{{3.0, 1.5}, 0.3}, {{2.0, -3.0 + 0.1 * k}, 0.2}};
    LaserScan scan = sim::raycast(w, Pose2{}, g);
    scan.stamp_s = 200.0 + 0.1 * k;
    const sensor_msgs::LaserScan msg = to_ros(scan, "laser");
    bag.write("/scan", msg.header.stamp, msg);
  }
  return path;
}

LaserScan read_scan(const std::string& bag_path, std::size_t index) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/scan"));
  std::size_t k = 0;
  for (const rosbag::MessageInstance& m : view) {
    if (k++ == index) return from_ros(*m.instantiate<sensor_msgs::LaserScan>());
  }
  throw std::runtime_error("no scan");
}

TEST(RenderScan, ObjectsInTheirColoursDynamicTrackAndMaskedSectorShaded) {
  RenderOptions o;
  o.input = write_scan_bag("scan.bag");
  o.output = temp_path("scan.png");
  o.view = "scan";
  o.scan_index = 30;
  o.static_sensor = true;
  const std::string config = temp_path("masked.yaml");
  std::ofstream(config) << "segmentation:\n  masked_sectors: [[1.9, 2.2]]\n";
  o.config_path = config;
  const RenderResult r = render_bag(o);
  ASSERT_TRUE(exists(o.output));
  const Picture pic(o.output);
  ASSERT_TRUE(pic.ok());
  EXPECT_EQ(pic.width(), 1600);
  EXPECT_EQ(pic.height(), 1200);

  // The segmentation as the renderer runs it: the pillar is one object.
  const LaserScan scan = read_scan(o.input, 30);
  DynamicFilterConfig c = DynamicFilterConfig{};
  c.segmentation.masked_sectors = {{1.9, 2.2}};
  const Segmentation seg = Segmenter(c.segmentation).segment(scan);
  EXPECT_EQ(r.objects, static_cast<std::int64_t>(seg.objects.size()));
  int checked = 0;
  for (std::size_t obj = 0; obj < seg.objects.size(); ++obj) {
    const Eigen::Vector2d centroid = seg.objects[obj].centroid_m;
    const bool pillar = (centroid - Eigen::Vector2d(3.0, 1.5)).norm() < 0.4;
    const bool person = (centroid - Eigen::Vector2d(2.0, 0.0)).norm() < 0.4;
    if (!pillar && !person) continue;
    // A beam of the object away from every track's ring.
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (seg.beam_labels[i] != static_cast<std::int32_t>(obj)) continue;
      const double b = scan.bearing_rad(i);
      const Eigen::Vector2d px =
          r.transform.to_pixel({scan.ranges_m[i] * std::cos(b), scan.ranges_m[i] * std::sin(b)});
      bool clear = true;
      for (const DrawnTrack& t : r.tracks) {
        const double d = (r.transform.to_pixel(t.position_m) - px).norm();
        if (std::abs(d - r.track_ring_radius_px) < 6.0) clear = false;
        if ((r.transform.to_pixel(t.position_m + t.velocity_mps) - px).norm() < 20.0) clear = false;
      }
      if (!clear) continue;
      EXPECT_EQ(pic.at(px), object_colour(obj)) << "object " << obj << ": " << describe(pic.at(px));
      ++checked;
      break;
    }
  }
  EXPECT_EQ(checked, 2);

  // The walking person is tracked as dynamic, moving along +y, with its ring drawn in red.
  const DrawnTrack* walker = nullptr;
  for (const DrawnTrack& t : r.tracks) {
    if ((t.position_m - Eigen::Vector2d(2.0, 0.0)).norm() < 0.35 && t.seen) walker = &t;
  }
  ASSERT_NE(walker, nullptr);
  EXPECT_EQ(walker->object_class, ObjectClass::kDynamic);
  EXPECT_GT(walker->velocity_mps.y(), 0.5);
  const Eigen::Vector2d ring =
      r.transform.to_pixel(walker->position_m) - Eigen::Vector2d(r.track_ring_radius_px, 0.0);
  EXPECT_TRUE(pic.near(ring, colours::kDynamic, 1));

  // The masked sector (1.9 to 2.2 rad) is shaded; the same distance outside it is background.
  const auto at_bearing = [&](double bearing) {
    return r.transform.to_pixel({1.0 * std::cos(bearing), 1.0 * std::sin(bearing)});
  };
  EXPECT_EQ(pic.at(at_bearing(2.05)), colours::kMaskedSector);
  EXPECT_EQ(pic.at(at_bearing(-2.05)), colours::kBackground);
  std::remove(o.input.c_str());
  std::remove(o.output.c_str());
  std::remove(config.c_str());
}

// --- Bad input ---------------------------------------------------------------------------------

void expect_render_error(const RenderOptions& o, const std::string& expected) {
  std::remove(o.output.c_str());
  try {
    render_bag(o);
    ADD_FAILURE() << "accepted; expected: " << expected;
  } catch (const JobError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(expected), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_FALSE(exists(o.output)) << expected;
  EXPECT_FALSE(exists(o.output + ".partial")) << expected;
}

TEST(RenderBadInput, OneLineErrorAndNoOutputFile) {
  const std::string bag = write_map_bag("bad_input.bag", {});
  const std::string out = temp_path("bad.png");
  RenderOptions o = map_options(bag, out);

  RenderOptions view = o;
  view.view = "top";
  expect_render_error(view, "unknown view 'top'");

  RenderOptions index = o;
  index.view = "scan";
  index.scan_index = 40;
  expect_render_error(index, "scan index 40 out of range: 40 scans on /scan");

  RenderOptions window = o;
  window.from_s = 100.0;
  window.to_s = 200.0;
  expect_render_error(window, "no scans on /scan_labels between 100 s and 200 s");
  window.from_s = 3.0;
  window.to_s = 2.0;
  expect_render_error(window, "no scans on /scan_labels between 3 s and 2 s");

  RenderOptions missing = o;
  missing.input = temp_path("no_such.bag");
  expect_render_error(missing, "no_such.bag: No such file or directory");

  const std::string text = temp_path("not_a_bag.bag");
  std::ofstream(text) << "hello\n";
  RenderOptions not_bag = o;
  not_bag.input = text;
  expect_render_error(not_bag, "not a readable ROS 1 bag");

  RenderOptions topic = o;
  topic.scan_topic = "/front";
  expect_render_error(topic, "no sensor_msgs/LaserScan topic /front");

  RenderOptions format = o;
  format.output = temp_path("bad.jpg");
  expect_render_error(format, "unknown picture format");

  RenderOptions frame = o;
  frame.frame = "truth";
  expect_render_error(frame, "no nav_msgs/Odometry topic /ground_truth");

  std::remove(bag.c_str());
  std::remove(text.c_str());
}

TEST(RenderBadInput, ImageSizeIsParsedAndChecked) {
  EXPECT_EQ(parse_image_size("1600x1200"), std::make_pair(1600, 1200));
  for (const char* bad : {"1600", "x1200", "100x100", "1600x1200x3", "-1600x1200", "axb"}) {
    EXPECT_THROW(parse_image_size(bad), JobError) << bad;
  }
}

// --- Evaluation plot ---------------------------------------------------------------------------

TEST(RenderPlot, RateBarsAndLatencyHistogram) {
  eval::Rates r;
  r.static_beams = 1000;
  r.static_kept = 990;
  r.moving_beams = 500;
  r.moving_removed = 250;
  r.scans = 10;
  r.actors_seen = 5;
  r.actors_removed = 4;
  r.latencies_s = {0.2, 0.4, 0.4, 1.0};
  const std::string out = temp_path("eval.png");
  const PlotLayout layout = plot_evaluation(r, "test", out, 1200, 800);
  const Picture pic(out);
  ASSERT_TRUE(pic.ok());
  EXPECT_EQ(pic.width(), 1200);
  EXPECT_EQ(pic.height(), 800);
  ASSERT_EQ(layout.bars.size(), 3u);
  const double unit = layout.zero_v_px - layout.one_v_px;
  EXPECT_NEAR(layout.bars[0].height / unit, 0.99, 1e-9);
  EXPECT_NEAR(layout.bars[1].height / unit, 0.5, 1e-9);
  EXPECT_EQ(layout.bars[2].width, 0.0);  // No still beams: no rate.
  for (const PlotLayout::Bar& bar : {layout.bars[0], layout.bars[1]}) {
    EXPECT_EQ(pic.at({bar.x + bar.width / 2.0, bar.y + bar.height / 2.0}), kPlotBar);
  }
  // Above the half-height rejection bar, at its left edge: nothing.
  const PlotLayout::Bar& b = layout.bars[1];
  EXPECT_EQ(pic.at({b.x + 3.0, b.y - 0.25 * unit}), colours::kBackground);
  // The histogram's bars are in the left half.
  int histogram = 0;
  for (int v = 0; v < 800; v += 2) {
    for (int u = 0; u < 600; u += 2) histogram += pic.at(u, v) == kPlotHistogram ? 1 : 0;
  }
  EXPECT_GT(histogram, 200);
  std::remove(out.c_str());
}

TEST(RenderPlot, UnknownFormatIsAnErrorWithoutOutput) {
  const std::string out = temp_path("eval.gif");
  EXPECT_THROW(plot_evaluation(eval::Rates{}, "x", out), JobError);
  EXPECT_FALSE(exists(out));
  EXPECT_FALSE(exists(out + ".partial"));
}

}  // namespace
}  // namespace dispel::render
