#pragma once
/// @file
/// `dispel sim`: a simulation written as a recording (the topics are in docs/simulator.md),
/// streamed as it is made (simulate_to_recording) or from a run held in memory (write_simulation);
/// both write through the one SimulationWriter.

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "dispel/jobs/job.hpp"
#include "dispel/sim/simulator.hpp"

namespace dispel::jobs {

/// Writes a simulation's topics to a recording: /scan, /scan_truth (intensities = ground-truth
/// codes), /scan_truth_actor (intensities = index of the actor hit + 1, 0 for none), /odom (wheel
/// odometry), /wheels (JointState velocity = [left, right] m/s), /imu (angular_velocity.z;
/// orientation unknown, covariance[0] = -1), /ground_truth (Odometry) and /tf_static (base_link ->
/// laser, at the scenario's start time, written first), LZ4-compressed. Scans and samples are
/// given in time order (at the same instant the scan first), as simulate() streams them. Written
/// to "<path>.partial" and renamed by finish(); destroyed without finish() (an error, JobCancelled)
/// it removes the partial file.
class SimulationWriter {
 public:
  /// @throws JobError when the file cannot be started.
  SimulationWriter(const sim::Scenario& scenario, const std::string& path);
  ~SimulationWriter();
  SimulationWriter(const SimulationWriter&) = delete;
  SimulationWriter& operator=(const SimulationWriter&) = delete;

  /// @throws JobError
  void scan(const sim::ScanFrame& frame);
  void sensor(const sim::SensorSample& sample);
  void finish();

 private:
  float scan_time_s_;
  std::unique_ptr<io::RecordingWriter> out_;
};

/// Writes @p run (held in memory) through SimulationWriter; when @p cancel becomes true, or on an
/// error, the partial file is removed. @throws JobError, JobCancelled
void write_simulation(const sim::SimulationOutput& run, const sim::Scenario& scenario,
                      const std::string& path, const std::atomic<bool>* cancel = nullptr);

/// What a streamed run wrote.
struct SimulationSummary {
  std::int64_t scans = 0;
  std::int32_t actor_count = 0;
  std::array<std::int64_t, 4> beams{};  ///< Per sim::Truth code.
};

/// About how many bytes the bag of a run of @p duration_s (already checked, sim::run_duration)
/// takes on disk: the messages' serialized sizes and the bag's records, times the LZ4 factor
/// measured on simulated bags (docs/simulator.md, "Bounds").
double estimate_recording_bytes(const sim::Scenario& scenario, double duration_s);

/// Runs the simulation (sim::simulate's streamed form) and writes each scan and sample as it is
/// made: memory does not grow with the duration (but for the bag library's index: a few dozen
/// bytes per message). Before any work it refuses a duration that sim::run_duration refuses and
/// a run whose bag would not fit in the free space of @p path's folder (statvfs; by
/// estimate_recording_bytes; not checked for a device such as /dev/null), naming the duration
/// and both sizes. Written to "<path>.partial" and renamed when complete; when @p cancel becomes
/// true, or on an error, the partial file is removed. @throws JobError, JobCancelled
SimulationSummary simulate_to_recording(const sim::Scenario& scenario, std::uint64_t seed,
                                        double duration_s, const std::string& path,
                                        const std::atomic<bool>* cancel = nullptr);

}  // namespace dispel::jobs
