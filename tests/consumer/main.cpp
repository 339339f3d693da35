// Segments a small scan through the installed dispel::core; exits 0 when one object is found.
#include <dispel/core/segmentation.hpp>

int main() {
  dispel::LaserScan scan;
  scan.angle_min_rad = -0.5;
  scan.angle_increment_rad = 0.01;
  scan.range_min_m = 0.1F;
  scan.range_max_m = 30.0F;
  scan.ranges_m.assign(50, 2.0F);
  dispel::Segmenter segmenter{dispel::SegmentationConfig{}};
  const dispel::Segmentation result = segmenter.segment(scan);
  return result.issue == dispel::ScanIssue::kNone && result.objects.size() == 1 ? 0 : 1;
}
