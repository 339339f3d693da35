// Segments a small scan through the installed dispel::core and filters it through the installed
// dispel::pipeline; exits 0 when one object is found and the scan comes through filtered.
#include <dispel/core/segmentation.hpp>
#include <dispel/pipeline/scan_filter_runner.hpp>

int main() {
  dispel::LaserScan scan;
  scan.angle_min_rad = -0.5;
  scan.angle_increment_rad = 0.01;
  scan.range_min_m = 0.1F;
  scan.range_max_m = 30.0F;
  scan.ranges_m.assign(50, 2.0F);
  dispel::Segmenter segmenter{dispel::SegmentationConfig{}};
  const dispel::Segmentation result = segmenter.segment(scan);
  dispel::pipeline::ScanFilterRunner runner({});
  const dispel::FilterResult& filtered = runner.process(scan, 0.0, dispel::Pose2{});
  return result.issue == dispel::ScanIssue::kNone && result.objects.size() == 1 &&
                 runner.last_outcome() == dispel::pipeline::ScanOutcome::kFiltered &&
                 filtered.labels.size() == scan.size()
             ? 0
             : 1;
}
