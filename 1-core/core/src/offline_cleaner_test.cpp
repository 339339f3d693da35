#include "dispel/core/offline_cleaner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace dispel {
namespace {

// Scan @p k of a still scanner at 10 Hz, 101 beams from -0.5 rad, no ranges yet.
LaserScan still_scan(int k, float range_max_m) {
  LaserScan s;
  s.stamp_s = 100.0 + 0.1 * k;
  s.angle_min_rad = -0.5;
  s.angle_increment_rad = 0.01;
  s.range_min_m = 0.1F;
  s.range_max_m = range_max_m;
  return s;
}

// A still scanner facing a wall 5 m away; for the first 20 scans a box stands 2 m in front of it
// over beams 40-60, then it is gone and the scanner sees the wall there.
LaserScan scan_at(int k) {
  LaserScan s = still_scan(k, 30.0F);
  for (int b = 0; b < 101; ++b) {
    const double bearing = s.angle_min_rad + s.angle_increment_rad * b;
    const bool box = k < 20 && b >= 40 && b <= 60;
    s.ranges_m.push_back(static_cast<float>((box ? 2.0 : 5.0) / std::cos(bearing)));
  }
  return s;
}

FilterResult all_static(const LaserScan& scan) {
  FilterResult r;
  r.labels.assign(scan.size(), BeamLabel::kNoObject);
  r.sensor_pose = Pose2{};
  return r;
}

// A finished cleaner that was given @p scans scans, @p scan_of(k), in none of which the online
// filter found anything.
template <typename ScanOf>
OfflineCleaner cleaned_all_static(const CleanConfig& config, int scans, ScanOf scan_of) {
  OfflineCleaner cleaner(config);
  for (int k = 0; k < scans; ++k) {
    const LaserScan s = scan_of(k);
    cleaner.add(s, all_static(s));
  }
  cleaner.finish();
  return cleaner;
}

// A box that stood 2 s and left, and (scan_at() backwards) one that came and stayed to the end.
// With exact poses (a still scanner), every beam of the box: scans at another time saw through
// its place, 2 in a row with no hit among them; the scans between, which saw it there, do not end
// the look. Otherwise the first hit ends it: only the box's beams from 1 s (through_gap_s) before
// it left, or within 1 s after it came.
TEST(OfflineCleaner, WhatStoodWhereTheScannerSawThroughAtAnotherTimeIsRemovedWhenAsked) {
  for (const bool came : {false, true}) {
    const auto scan_of = [came](int k) {
      LaserScan s = scan_at(came ? 39 - k : k);
      s.stamp_s = 100.0 + 0.1 * k;
      return s;
    };
    for (const bool exact : {false, true}) {
      for (const int through_scans : {0, 2}) {
        CleanConfig config;
        config.through_min_scans = through_scans;
        config.poses_exact = exact;
        OfflineCleaner cleaner = cleaned_all_static(config, 40, scan_of);
        std::vector<CleanLabel> labels;
        for (int k = 0; k < 40; ++k) {
          const LaserScan s = scan_of(k);
          cleaner.label(static_cast<std::size_t>(k), s, labels);
          for (int b = 0; b < 101; ++b) {
            const bool box = (came ? k >= 20 : k < 20) && b >= 40 && b <= 60;
            const bool seen = exact || (came ? k < 30 : k >= 10);
            EXPECT_EQ(labels[b], box && seen && through_scans > 0 ? CleanLabel::kVacated
                                                                  : CleanLabel::kNoObject)
                << (came ? "came, " : "left, ") << (exact ? "exact, " : "") << "scan " << k
                << " beam " << b;
          }
        }
        EXPECT_EQ(cleaner.counts().vacated, through_scans > 0 ? (exact ? 20 : 10) * 21 : 0);
      }
    }
  }
}

// Things that stay, with a scanner's flicker: a post 2 m away that returns nothing in one scan
// of every seven (never 2 in a row), and a dark board 0.1 m short of the range limit (5.6 m) that
// returns nothing in runs of three scans (a beam that returns nothing near its range limit may
// have passed a surface too dark to return it). Neither place is seen through.
TEST(OfflineCleaner, AFlickeringPostAndADarkBoardAtTheRangeLimitStay) {
  const auto scan_of = [](int k) {
    LaserScan s = still_scan(k, 5.6F);
    const float none = std::numeric_limits<float>::infinity();
    for (int b = 0; b < 101; ++b) {
      float r = none;  // The open room beyond the range limit.
      if (b >= 20 && b <= 26) r = k % 7 == 3 ? none : 2.0F;
      if (b >= 60 && b <= 70) r = k % 6 < 3 ? none : 5.5F;
      s.ranges_m.push_back(r);
    }
    return s;
  };
  CleanConfig config;
  config.through_min_scans = 2;
  config.poses_exact = true;  // The walk looks past hits: the flicker must be 2 in a row.
  OfflineCleaner cleaner = cleaned_all_static(config, 200, scan_of);
  std::vector<CleanLabel> labels;
  for (int k = 0; k < 200; ++k) {
    cleaner.label(static_cast<std::size_t>(k), scan_of(k), labels);
  }
  EXPECT_EQ(cleaner.counts().vacated, 0);
  EXPECT_GT(cleaner.counts().valid_beams, 200 * 7 * 6 / 7 + 200 * 11 / 2 - 100);
}

// Beams @p first to @p last of @p scan as one object tracked as @p id at @p position, labelled
// dynamic or static.
FilterResult tracked(const LaserScan& scan, int first, int last, std::uint64_t id,
                     const Eigen::Vector2d& position, bool dynamic) {
  FilterResult r = all_static(scan);
  Segmentation& seg = r.segmentation;
  seg.beam_labels.assign(scan.size(), kLabelNoise);
  ScanObject thing;
  thing.first_beam = first;
  thing.last_beam = last;
  thing.point_count = last - first + 1;
  const auto at = [&](int b) -> Eigen::Vector2d {
    const double bearing = scan.angle_min_rad + scan.angle_increment_rad * b;
    return static_cast<double>(scan.ranges_m[static_cast<std::size_t>(b)]) *
           Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
  };
  thing.first_point_m = at(first);
  thing.last_point_m = at(last);
  seg.objects.push_back(thing);
  for (int b = first; b <= last; ++b) {
    seg.beam_labels[static_cast<std::size_t>(b)] = 0;
    r.labels[static_cast<std::size_t>(b)] = dynamic ? BeamLabel::kDynamic : BeamLabel::kStatic;
  }
  TrackedObject t;
  t.id = id;
  t.object_class = dynamic ? ObjectClass::kDynamic : ObjectClass::kStatic;
  t.position_m = position;
  t.object_index = 0;
  r.tracks.push_back(t);
  return r;
}

// The box of scan_at() as one object tracked as @p id at @p position, labelled dynamic or static.
FilterResult box_tracked(const LaserScan& scan, std::uint64_t id, const Eigen::Vector2d& position,
                         bool dynamic) {
  return tracked(scan, 40, 60, id, position, dynamic);
}

// Someone who stood in no object (scans 0-19, 10 Hz, at (2, 0) before a wall 5 m away) and
// then walked off on a track of their own (7, found moving from scan 20, 0.5 m/s along y). Nothing
// links the two but the place: the track set off where the person stood, and the place was left
// after. Within 0.5 m of it stand a post (hit after: it stays), and a small thing that flickers
// (hit in every other scan before the track set off, as a scan plane meets a low thing now and
// then: it stays although it is gone after).
TEST(OfflineCleaner, WhatStoodWhereATrackSetOffLaterIsRemoved) {
  const auto unit = [](int b) {
    const double bearing = -0.5 + 0.01 * b;
    return Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
  };
  // Where beam @p b meets a disc of @p radius at @p c, or infinity.
  const auto disc = [&](int b, const Eigen::Vector2d& c, double radius) {
    const double along = c.dot(unit(b));
    return (along * unit(b) - c).norm() <= radius ? along : HUGE_VAL;
  };
  const Eigen::Vector2d post(2.2, 0.4), flicker(1.8, -0.42);
  const auto person = [](int k) { return Eigen::Vector2d(2.0, k < 20 ? 0.0 : 0.05 * (k - 20)); };
  enum Thing { kWall, kPerson, kPost, kFlicker };
  const auto thing_of = [&](int k, int b) {
    double r = 5.0 / unit(b).x();
    Thing what = kWall;
    const auto nearer = [&](double d, Thing t) {
      if (d < r) {
        r = d;
        what = t;
      }
    };
    nearer(disc(b, person(k), 0.2), kPerson);
    nearer(disc(b, post, 0.1), kPost);
    if (k < 20 && k % 2 == 0) nearer(disc(b, flicker, 0.08), kFlicker);
    return std::make_pair(what, r);
  };
  const auto scan_of = [&](int k) {
    LaserScan s = still_scan(k, 30.0F);
    for (int b = 0; b < 101; ++b) s.ranges_m.push_back(static_cast<float>(thing_of(k, b).second));
    return s;
  };
  OfflineCleaner cleaner{CleanConfig{}};
  for (int k = 0; k < 40; ++k) {
    const LaserScan s = scan_of(k);
    if (k < 20) {
      cleaner.add(s, all_static(s));  // The standing person in no object.
      continue;
    }
    int first = -1, last = -1;
    for (int b = 0; b < 101; ++b) {
      if (thing_of(k, b).first != kPerson) continue;
      if (first < 0) first = b;
      last = b;
    }
    ASSERT_GE(first, 0) << "scan " << k;
    cleaner.add(s, tracked(s, first, last, 7, person(k), true));
  }
  cleaner.finish();
  std::vector<CleanLabel> labels;
  int person_kept = 0, post_removed = 0, flicker_removed = 0, flicker_beams = 0, wall_removed = 0;
  for (int k = 0; k < 20; ++k) {
    cleaner.label(static_cast<std::size_t>(k), scan_of(k), labels);
    for (int b = 0; b < 101; ++b) {
      const bool gone = removed(labels[static_cast<std::size_t>(b)]);
      switch (thing_of(k, b).first) {
        case kPerson:
          person_kept += gone || k == 19 ? 0 : 1;
          if (gone) {
            EXPECT_EQ(labels[static_cast<std::size_t>(b)], CleanLabel::kMovedLater);
          }
          break;
        case kPost:
          post_removed += gone ? 1 : 0;
          break;
        case kFlicker:
          ++flicker_beams;
          flicker_removed += gone ? 1 : 0;
          break;
        case kWall:
          wall_removed += gone ? 1 : 0;
          break;
      }
    }
  }
  // All but the last scan before it set off: no scan between them tells that it stood.
  EXPECT_EQ(person_kept, 0);
  EXPECT_EQ(post_removed, 0);
  EXPECT_GT(flicker_beams, 10);
  EXPECT_EQ(flicker_removed, 0);
  EXPECT_EQ(wall_removed, 0);
}

// A still sensor's walks skip the blocks of scans that cannot see through a place (reach_cm_):
// the labels must be those of walks that look at every scan. 40 s at 10 Hz: a post that
// returns nothing in one scan of seven, a board near the range limit that returns nothing in
// runs of three, a box that stands 12 s 0.4 m before the wall and leaves (the wall's beams
// then reach 0.1 m beyond it), one that comes at 25 s and stays, and a thing crossing the beams.
// The same scans with one pose moved by 1 nm walk every scan.
TEST(OfflineCleaner, AStillSensorsWalksThatSkipScansGiveTheSameLabels) {
  const auto scan_of = [](int k) {
    LaserScan s = still_scan(k, 5.6F);
    const float none = std::numeric_limits<float>::infinity();
    for (int b = 0; b < 101; ++b) {
      float r = b < 50 ? 4.0F : none;  // A wall on one side, the open room on the other.
      if (b >= 10 && b <= 14) r = k % 7 == 3 ? none : 2.0F;        // The post.
      if (b >= 60 && b <= 70) r = k % 6 < 3 ? none : 5.5F;         // The board.
      if (b >= 20 && b <= 30 && k < 120) r = 3.6F;                 // Stands, leaves.
      if (b >= 75 && b <= 85 && k >= 250) r = 3.0F;                // Comes, stays.
      if (std::abs(b - (k % 100)) <= 2 && k % 100 < 95) r = 1.0F;  // Crosses.
      s.ranges_m.push_back(r);
    }
    return s;
  };
  CleanConfig config;
  config.through_min_scans = 2;
  config.poses_exact = true;
  std::vector<std::vector<CleanLabel>> by_walk[2];
  std::int64_t vacated[2] = {0, 0};
  for (const int nudged : {0, 1}) {
    OfflineCleaner cleaner(config);
    for (int k = 0; k < 400; ++k) {
      const LaserScan s = scan_of(k);
      FilterResult r = all_static(s);
      if (nudged == 1 && k == 200) r.sensor_pose = Pose2{1e-9, 0.0, 0.0};
      cleaner.add(s, r);
    }
    cleaner.finish();
    std::vector<CleanLabel> labels;
    for (int k = 0; k < 400; ++k) {
      cleaner.label(static_cast<std::size_t>(k), scan_of(k), labels);
      by_walk[nudged].push_back(labels);
    }
    vacated[nudged] = cleaner.counts().vacated;
  }
  EXPECT_GT(vacated[0], 120 * 11 / 2);  // At least half the box that stood and left.
  EXPECT_EQ(vacated[0], vacated[1]);
  for (int k = 0; k < 400; ++k) {
    if (k == 200) continue;  // The nudged scan's own place moved by 1 nm.
    ASSERT_EQ(by_walk[0][static_cast<std::size_t>(k)], by_walk[1][static_cast<std::size_t>(k)])
        << "scan " << k;
    const LaserScan s = scan_of(k);
    for (int b = 10; b <= 14; ++b) {
      if (s.ranges_m[static_cast<std::size_t>(b)] != 2.0F) continue;  // Crossed, or no return.
      EXPECT_FALSE(removed(by_walk[0][static_cast<std::size_t>(k)][static_cast<std::size_t>(b)]))
          << "the post, scan " << k;
    }
  }
}

// negative_2 (a real robot, laser-only, no people): a track dynamic for three scans in which it
// hardly moved, whose centroid then slid 2-4 m while it was static (a wall piece on drifting
// poses), counted as moving by its travel from where it was first seen and kept its false
// removals. Travel counts only while dynamic: it never moved, and its beams are restored. A
// track that moved 0.3 m a scan while dynamic moved.
TEST(OfflineCleaner, ATrackMovedOnlyIfItTravelledWhileFoundDynamic) {
  for (const double step_while_dynamic : {0.0, 0.3}) {
    OfflineCleaner cleaner{CleanConfig{}};
    for (int k = 0; k < 20; ++k) {
      const LaserScan s = scan_at(0);  // The box stays; only the track's centroid moves.
      const bool dynamic = k < 3;
      const Eigen::Vector2d position =
          dynamic ? Eigen::Vector2d{2.0, step_while_dynamic * k} : Eigen::Vector2d{2.0, 0.2 * k};
      LaserScan at_k = s;
      at_k.stamp_s = 100.0 + 0.1 * k;
      cleaner.add(at_k, box_tracked(at_k, 7, position, dynamic));
    }
    cleaner.finish();
    const std::vector<CleanedObject> objects = cleaner.objects();  // A copy: keep it.
    ASSERT_EQ(objects.size(), 1U);
    const CleanedObject& o = objects.front();
    EXPECT_EQ(o.dynamic_scans, 3);
    EXPECT_NEAR(o.travel_m, 3.8, 1e-9);
    EXPECT_NEAR(o.dynamic_travel_m, 2 * step_while_dynamic, 1e-6);
    const bool moved = step_while_dynamic > 0.0;
    EXPECT_EQ(o.moving, moved);
    std::vector<CleanLabel> labels;
    LaserScan first = scan_at(0);
    cleaner.label(0, first, labels);
    EXPECT_EQ(labels[50], moved ? CleanLabel::kDynamic : CleanLabel::kRestored);
  }
}

// A still scanner (10 Hz, 201 beams over 2 rad) before a wall 5 m away. A person (0.4 m wide)
// walks across it 2 m away at 1 m/s, from y = -1.8 to 3 (scans 0-48). The online filter
// finds the person moving only from scan 30 (y = 1.2), as it does for someone walking in at
// range, and to the end: it moved 1.8 m while dynamic. In scans 20-29 the person is within
// moved_from_m (1 m) of where the track was found moving; in scans 0-19 the track walked there from
// farther. In the second case a post at (3.5, -5) is on that track in scans 0-19, and the track
// then jumps to the passer-by (on another track before): the post did not walk, and stays.
struct Walkin {
  static constexpr int kScans = 49;
  static constexpr int kFoundMoving = 30;
  static constexpr int kBeams = 201;
  static double person_y(int k) { return -1.8 + 0.1 * k; }
  static Eigen::Vector2d unit(int b) {
    const double bearing = -1.0 + 0.01 * b;
    return {std::cos(bearing), std::sin(bearing)};
  }
  // Where beam @p b meets the post (0.1 m radius at (3.5, -5)), or infinity.
  static double post_range(int b) {
    const Eigen::Vector2d post(3.5, -5.0);
    const double along = post.dot(unit(b));
    return (along * unit(b) - post).norm() <= 0.1 ? along : HUGE_VAL;
  }
  static bool on_person(int k, int b) {
    const Eigen::Vector2d u = unit(b);
    return std::abs(2.0 / u.x() * u.y() - person_y(k)) <= 0.2;
  }
  static LaserScan scan(int k) {
    LaserScan s = still_scan(k, 30.0F);
    s.angle_min_rad = -1.0;
    for (int b = 0; b < kBeams; ++b) {
      const double to_wall = 5.0 / unit(b).x();
      const double r = on_person(k, b) ? 2.0 / unit(b).x() : std::min(to_wall, post_range(b));
      s.ranges_m.push_back(static_cast<float>(r));
    }
    return s;
  }
  // The first and last beam of what @p hit says.
  template <typename Hit>
  static std::pair<int, int> beams(Hit hit) {
    std::pair<int, int> span{-1, -1};
    for (int b = 0; b < kBeams; ++b) {
      if (!hit(b)) continue;
      if (span.first < 0) span.first = b;
      span.second = b;
    }
    return span;
  }
};

TEST(OfflineCleaner, APersonWhoseTrackWalkedInFromFarIsRemovedFromTheFirstScanAndAPostStays) {
  const auto [post_first, post_last] =
      Walkin::beams([](int b) { return std::isfinite(Walkin::post_range(b)); });
  ASSERT_GE(post_first, 0);
  for (const bool takeover : {false, true}) {
    SCOPED_TRACE(takeover ? "a post's track takes the passer-by over" : "one track walks in");
    OfflineCleaner cleaner{CleanConfig{}};
    std::vector<LaserScan> scans;
    for (int k = 0; k < Walkin::kScans; ++k) {
      scans.push_back(Walkin::scan(k));
      const LaserScan& s = scans.back();
      const auto [first, last] = Walkin::beams([k](int b) { return Walkin::on_person(k, b); });
      ASSERT_GE(first, 0);
      ASSERT_LT(post_last, first);
      // The person's track: 7 throughout, or 7 (the post's until then) from scan 20 on.
      const std::uint64_t person_track = takeover && k < 20 ? 11 : 7;
      FilterResult r = tracked(s, first, last, person_track, {2.0, Walkin::person_y(k)},
                               k >= Walkin::kFoundMoving);
      if (takeover) {  // The post as a second object.
        const FilterResult post =
            tracked(s, post_first, post_last, k < 20 ? 7 : 12, {3.5, -5.0}, false);
        for (int b = post_first; b <= post_last; ++b) {
          r.segmentation.beam_labels[static_cast<std::size_t>(b)] = 1;
        }
        r.segmentation.objects.push_back(post.segmentation.objects.front());
        TrackedObject t = post.tracks.front();
        t.object_index = 1;
        r.tracks.push_back(t);
      }
      cleaner.add(s, r);
    }
    cleaner.finish();
    std::vector<CleanLabel> labels;
    int person_kept = 0, person_kept_far = 0, wall_removed = 0, post_removed = 0;
    for (int k = 0; k < Walkin::kScans; ++k) {
      cleaner.label(static_cast<std::size_t>(k), scans[static_cast<std::size_t>(k)], labels);
      for (int b = 0; b < Walkin::kBeams; ++b) {
        const bool gone = removed(labels[static_cast<std::size_t>(b)]);
        if (Walkin::on_person(k, b)) {
          person_kept += gone ? 0 : 1;
          person_kept_far += !gone && k < 20 ? 1 : 0;
        } else if (b >= post_first && b <= post_last) {
          post_removed += gone ? 1 : 0;
        } else {
          wall_removed += gone ? 1 : 0;
        }
      }
    }
    EXPECT_EQ(wall_removed, 0);
    EXPECT_EQ(post_removed, 0);
    // Track 7 walked into its stretch from its first sighting, or, in the second case, from
    // where it jumped from the post to the passer-by (scan 20).
    const auto objects = cleaner.objects();
    const auto seven = std::find_if(objects.begin(), objects.end(),
                                    [](const CleanedObject& o) { return o.track_id == 7; });
    ASSERT_NE(seven, objects.end());
    EXPECT_TRUE(seven->moving);
    EXPECT_EQ(seven->walking_scans, takeover ? 10 : 30);
    if (takeover) {
      EXPECT_GT(person_kept_far, 0);  // On another track before scan 20, one that never moved.
    } else {
      EXPECT_EQ(person_kept, 0);  // From the first scan, 3 m from where it was found moving.
    }
  }
}

// A still scanner (10 Hz) before a wall 8 m away, with a pane of glass (no return) over beams
// 170-200. A leg (0.06 m radius, 4 beams at 6 m: fewer than N_min, so in no object) stands at
// y = -1.5 until scan 10, walks to y = 0.5 at 1 m/s, and stands there from scan 30 to 39. A post
// stands at (5, 1.5). In the glass a single return (speckle) drifts 0.07 m a scan away from the
// scanner, as a driving robot's sporadic returns in the open drift with it: nothing returns on
// either side of it, so it is no leg.
struct LegScene {
  static constexpr int kScans = 40;
  static double leg_y(int k) { return -1.5 + 0.1 * std::clamp(k - 10, 0, 20); }
  static LaserScan scan(
      int k, std::vector<int>* what = nullptr) {  // what: 0 wall, 1 leg, 2 post, 3 speckle
    LaserScan s;
    s.stamp_s = 200.0 + 0.1 * k;
    s.angle_min_rad = -0.5;
    s.angle_increment_rad = 0.005;
    s.range_min_m = 0.1F;
    s.range_max_m = 30.0F;
    if (what != nullptr) what->assign(201, 0);
    const auto circle = [](double bearing, double cx, double cy, double radius) {
      const double ux = std::cos(bearing), uy = std::sin(bearing);
      const double along = cx * ux + cy * uy;
      const double off2 = cx * cx + cy * cy - along * along;
      if (off2 > radius * radius) return std::numeric_limits<double>::infinity();
      return along - std::sqrt(radius * radius - off2);
    };
    for (int b = 0; b < 201; ++b) {
      const double bearing = s.angle_min_rad + s.angle_increment_rad * b;
      double r =
          b >= 170 && b <= 200 ? std::numeric_limits<double>::infinity() : 8.0 / std::cos(bearing);
      int kind = 0;
      const double leg = circle(bearing, 6.0, leg_y(k), 0.06);
      const double post = circle(bearing, 5.0, 1.5, 0.06);
      if (leg < r) {
        r = leg;
        kind = 1;
      }
      if (post < r) {
        r = post;
        kind = 2;
      }
      if (b == 172 + k / 2) {
        r = 4.0 + 0.07 * k;
        kind = 3;
      }
      s.ranges_m.push_back(static_cast<float>(r));
      if (what != nullptr) (*what)[static_cast<std::size_t>(b)] = kind;
    }
    return s;
  }
};

// Legs at range: a leg in no object that walked is removed while it walked and, where the
// scanner then saw through its place, while it stood before; what it did after it last moved
// stays; a post and speckle stay.
TEST(OfflineCleaner, ALegInNoObjectThatWalkedIsRemovedAndAPostAndSpeckleStay) {
  for (const double leg_walk_m : {1.0, 0.0}) {
    CleanConfig config;
    config.leg_walk_m = leg_walk_m;
    OfflineCleaner cleaner =
        cleaned_all_static(config, LegScene::kScans, [](int k) { return LegScene::scan(k); });
    std::vector<CleanLabel> labels;
    std::int64_t leg_beams = 0, walked = 0;
    for (int k = 0; k < LegScene::kScans; ++k) {
      std::vector<int> what;
      const LaserScan s = LegScene::scan(k, &what);
      cleaner.label(static_cast<std::size_t>(k), s, labels);
      for (std::size_t b = 0; b < labels.size(); ++b) {
        if (what[b] == 1) {
          ++leg_beams;
          walked += labels[b] == CleanLabel::kWalkedLeg ? 1 : 0;
          // Standing at the start, walking (scans 10-30), and for 0.5 s after (the chain's motion
          // within half a second): removed. Standing at the end: kept.
          const bool removed_expected = leg_walk_m > 0.0 && k <= 34;
          if (k <= 30 || k >= 36) {
            EXPECT_EQ(labels[b], removed_expected ? CleanLabel::kWalkedLeg : CleanLabel::kNoObject)
                << "scan " << k << " beam " << b;
          }
        } else {
          EXPECT_EQ(labels[b], CleanLabel::kNoObject)
              << "scan " << k << " beam " << b << " what " << what[b];
        }
      }
    }
    EXPECT_GE(leg_beams, 3 * LegScene::kScans);  // 3-4 beams a scan.
    EXPECT_EQ(cleaner.counts().walked_legs, walked);
    EXPECT_EQ(walked > 0, leg_walk_m > 0.0);
  }
}

TEST(OfflineCleaner, BadParametersAndScansAreRefusedByName) {
  CleanConfig config;
  config.max_width_m = 0.0;
  EXPECT_THROW(
      {
        try {
          OfflineCleaner c(config);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("clean.max_width_m"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  OfflineCleaner cleaner{CleanConfig{}};
  const LaserScan s = scan_at(0);
  cleaner.add(s, all_static(s));
  cleaner.finish();
  std::vector<CleanLabel> labels;
  LaserScan shorter = s;
  shorter.ranges_m.pop_back();
  EXPECT_THROW(cleaner.label(0, shorter, labels), std::invalid_argument);
  EXPECT_THROW(cleaner.label(1, s, labels), std::out_of_range);
}

}  // namespace
}  // namespace dispel
