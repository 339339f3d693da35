#include "dispel/eval/beam_evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dispel::eval {

double Rates::quantile(double q) const {
  if (latencies_s.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> v = latencies_s;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const auto hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

void BeamEvaluator::add_scan(double stamp_s, const std::vector<std::uint8_t>& truth,
                             const std::vector<std::int32_t>& actor,
                             const std::vector<bool>& removed) {
  if (truth.size() != removed.size() || actor.size() != truth.size()) {
    throw std::invalid_argument("truth, actor and result have different beam counts");
  }
  ++rates_.scans;
  std::map<std::int32_t, std::pair<int, int>> moving_beams;  // actor -> (beams, removed)
  std::map<std::int32_t, std::pair<int, int>> still_beams;   // actor -> (beams, removed)
  for (std::size_t i = 0; i < truth.size(); ++i) {
    switch (truth[i]) {
      case kTruthStatic:
        ++rates_.static_beams;
        rates_.static_kept += removed[i] ? 0 : 1;
        break;
      case kTruthMoving:
        ++rates_.moving_beams;
        rates_.moving_removed += removed[i] ? 1 : 0;
        if (actor[i] > 0) {
          auto& [beams, rem] = moving_beams[actor[i]];
          ++beams;
          rem += removed[i] ? 1 : 0;
        }
        break;
      case kTruthStill:
        ++rates_.still_beams;
        rates_.still_removed += removed[i] ? 1 : 0;
        if (actor[i] > 0) {
          auto& [beams, rem] = still_beams[actor[i]];
          ++beams;
          rem += removed[i] ? 1 : 0;
        }
        break;
      default:
        break;
    }
  }
  for (const auto& [id, counts] : still_beams) {
    still_.push_back({id, stamp_s, counts.first, counts.second});
  }
  for (const auto& [id, counts] : moving_beams) {
    last_moving_s_[id] = stamp_s;
    if (counts.first < min_beams_) continue;
    ActorTimes& t = actors_[id];
    if (std::isnan(t.first_seen)) t.first_seen = stamp_s;
    if (std::isnan(t.first_removed) && 2 * counts.second >= counts.first) t.first_removed = stamp_s;
  }
}

Rates BeamEvaluator::result() const {
  Rates r = rates_;
  for (const StillScan& s : still_) {
    const auto last = last_moving_s_.find(s.actor);
    if (last == last_moving_s_.end() || !(s.stamp_s < last->second)) continue;
    r.still_moves_later_beams += s.beams;
    r.still_moves_later_removed += s.removed;
  }
  for (const auto& [id, t] : actors_) {
    ++r.actors_seen;
    if (!std::isnan(t.first_removed)) {
      ++r.actors_removed;
      r.latencies_s.push_back(t.first_removed - t.first_seen);
    }
  }
  return r;
}

}  // namespace dispel::eval
