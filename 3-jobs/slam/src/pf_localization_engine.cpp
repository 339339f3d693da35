// The MRPT side of dispel::slam's localisation: CMonteCarloLocalization2D stepped by
// CParticleFilter, one scan and one odometry increment at a time, in an occupancy grid.

#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>

#include <cmath>
#include <exception>
#include <mutex>
#include <utility>

#include "dispel/jobs/job.hpp"
#include "dispel/slam/localization.hpp"
#include "mrpt_convert.hpp"

namespace dispel::slam {
namespace {

using detail::first_line;
using mrpt::random::CRandomGenerator;

// MRPT's particle filter draws from the process-wide generator. A localizer swaps its own in for
// each call, under this lock, so that its numbers depend on its seed alone.
std::mutex& random_generator_mutex() {
  static std::mutex m;
  return m;
}

class OwnRandomNumbers {
 public:
  explicit OwnRandomNumbers(CRandomGenerator& own) : lock_(random_generator_mutex()), own_(own) {
    std::swap(mrpt::random::getRandomGenerator(), own_);
  }
  ~OwnRandomNumbers() { std::swap(mrpt::random::getRandomGenerator(), own_); }
  OwnRandomNumbers(const OwnRandomNumbers&) = delete;
  OwnRandomNumbers& operator=(const OwnRandomNumbers&) = delete;

 private:
  std::lock_guard<std::mutex> lock_;
  CRandomGenerator& own_;
};

}  // namespace

struct PfLocalizer::Impl {
  mrpt::maps::COccupancyGridMap2D::Ptr grid;
  mrpt::slam::CMonteCarloLocalization2D particles;
  mrpt::bayes::CParticleFilter filter;
  mrpt::obs::CActionRobotMovement2D::TMotionModelOptions motion;
  CRandomGenerator random;
  Pose2 grid_origin;  // The filter runs in the grid's frame: this is it in the map frame.
  bool started = false;
  Pose2 last_odometry;
};

PfLocalizer::PfLocalizer(const GridMap& map, const ParticleFilterOptions& o,
                         const Pose2& initial_pose)
    : impl_(std::make_unique<Impl>()) {
  map.validate();
  o.validate();
  Impl& m = *impl_;
  m.grid_origin = map.origin;
  m.grid = detail::to_mrpt_grid(map);
  auto& lik = m.grid->likelihoodOptions;
  lik.likelihoodMethod = mrpt::maps::COccupancyGridMap2D::lmLikelihoodField_Thrun;
  lik.LF_stdHit = static_cast<float>(o.likelihood_std_m);
  lik.LF_decimation = static_cast<std::uint32_t>(o.likelihood_decimation);
  lik.LF_maxCorrsDistance = static_cast<float>(o.likelihood_max_distance_m);
  lik.enableLikelihoodCache = true;
  m.particles.options.metricMap = m.grid;

  auto& pf = m.filter.m_options;
  pf.PF_algorithm = o.algorithm == PfAlgorithm::kAuxiliaryOptimal
                        ? mrpt::bayes::CParticleFilter::pfAuxiliaryPFOptimal
                        : mrpt::bayes::CParticleFilter::pfStandardProposal;
  pf.resamplingMethod = mrpt::bayes::CParticleFilter::prSystematic;
  pf.adaptiveSampleSize = false;
  pf.sampleSize = static_cast<unsigned int>(o.particles);
  pf.BETA = o.resample_below_ess;
  m.filter.setVerbosityLevel(mrpt::system::LVL_ERROR);
  m.particles.setVerbosityLevel(mrpt::system::LVL_ERROR);

  auto& g = m.motion.gaussianModel;
  m.motion.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
  g.minStdXY = o.motion_std_xy_m;
  g.minStdPHI = o.motion_std_yaw_rad;
  g.a1 = o.motion_std_xy_per_m;
  g.a2 = o.motion_std_xy_per_rad;
  g.a3 = o.motion_std_yaw_per_m;
  g.a4 = o.motion_std_yaw_per_rad;

  m.random.randomize(static_cast<std::uint32_t>(o.seed ^ (o.seed >> 32)));
  const OwnRandomNumbers own(m.random);
  auto& rng = mrpt::random::getRandomGenerator();
  m.particles.resetDeterministic(mrpt::math::TPose2D(0, 0, 0), pf.sampleSize);
  const Pose2 to_grid = m.grid_origin.inverse();
  for (auto& particle : m.particles.m_particles) {
    const Pose2 drawn{
        initial_pose.x_m + o.initial_std_x_m * rng.drawGaussian1D_normalized(),
        initial_pose.y_m + o.initial_std_y_m * rng.drawGaussian1D_normalized(),
        wrap_angle(initial_pose.yaw_rad + o.initial_std_yaw_rad * rng.drawGaussian1D_normalized())};
    const Pose2 p = to_grid * drawn;
    particle.d = mrpt::math::TPose2D(p.x_m, p.y_m, p.yaw_rad);
    particle.log_w = 0.0;
  }
}

PfLocalizer::~PfLocalizer() = default;

std::optional<PoseEstimate> PfLocalizer::process(const LaserScan& scan, const Pose2& odometry,
                                                 const Pose2& mount, std::int64_t* invalid_beams) {
  const auto obs = detail::to_mrpt_scan(scan, mount, invalid_beams);
  if (!obs) return std::nullopt;
  Impl& m = *impl_;

  Pose2 increment;
  if (m.started) increment = m.last_odometry.inverse() * odometry;
  m.started = true;
  m.last_odometry = odometry;

  const mrpt::obs::CActionCollection actions =
      detail::odometry_action(increment, obs->timestamp, m.motion);
  mrpt::obs::CSensoryFrame frame;
  frame.insert(obs);
  try {
    const OwnRandomNumbers own(m.random);
    m.filter.executeOn(m.particles, &actions, &frame);
  } catch (const std::exception& e) {
    throw jobs::JobError("particle filter: " + first_line(e));
  }
  const auto [cov, mean] = m.particles.getCovarianceAndMean();
  PoseEstimate out;
  out.pose = m.grid_origin * Pose2{mean.x(), mean.y(), mean.phi()};
  out.position_std_m = std::sqrt(std::max(0.0, cov(0, 0) + cov(1, 1)));
  out.yaw_std_rad = std::sqrt(std::max(0.0, cov(2, 2)));
  return out;
}

}  // namespace dispel::slam
