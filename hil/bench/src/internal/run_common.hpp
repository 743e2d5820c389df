// What the in-process and the two-process executors share: the resolved
// configuration, the CAN link by name, the result's bookkeeping.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "maglev/bench/candump_log.hpp"
#include "maglev/bench/overrides.hpp"
#include "maglev/bench/runner.hpp"
#include "maglev/bench/timeline.hpp"
#include "maglev/can_link/bus_load.hpp"
#include "maglev/can_port/periodic_timer.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

namespace maglev::bench::internal {

// The scenario's overrides on the defaults, then the command line's kernel
// and seed. false: *errors says why.
bool resolve_overrides(const scenario::Scenario& sc, const RunOptions& opt, Overrides* ov,
                       std::vector<ScenarioError>* errors);

RunResult new_result(const scenario::Scenario& sc, const Overrides& ov);

struct Link {
  std::shared_ptr<can::VirtualBus> bus;  // --can virtual: a private bus per run
  std::unique_ptr<can::OwnedCanPort> plant_port, ctrl_port;
  std::string error;
};
Link open_link(const std::string& name, bool need_controller);

// --can-log: a listen-only port on the link's bus (another endpoint of the
// virtual bus, or another socket on the interface): it receives every frame
// the plant and the controller send and never sends, so the run is unchanged.
// The log's interface name is the --can name ("virtual" for the in-process bus).
struct CanLogTap {
  std::unique_ptr<can::OwnedCanPort> port;
  CandumpLogWriter log;
  std::uint64_t period_us = 400;  // the servo period (set by the run from its rate)
  // Simulated time of tick n in microseconds, exact (n x the servo period).
  std::uint64_t tick_time_us(std::uint64_t n) const;
  // Logs every frame the tap has received, stamped with tick n's time.
  void drain(std::uint64_t n);
};
// false: *error says why (the tap is not open).
bool open_can_log(const Link& link, const std::string& can_name, const std::string& path, CanLogTap* tap,
                  std::string* error);

// Wall time, tick count, real-time factor and bus load of a finished run.
// Returns the simulated time [s].
double set_run_timing(RunResult* R, double wall_s, const can::BusLoadMeter& meter, double dt);
// This thread's CPU time, s (CLOCK_THREAD_CPUTIME_ID; 0 where unavailable).
double thread_cpu_s();

// What the metrics need from the link and the kernel at the end of a run.
struct LinkTotals {
  std::uint64_t missed_actuator_frames;
  std::uint32_t controller_rx_rejected;
  std::uint32_t plant_rx_rejected;
  double final_sequencer_state;
  double fault_code;
};
// The run metrics both modes report (R's timing and completed already set).
void add_run_metrics(RunResult* R, const can::BusLoadMeter& meter, double sim_s, const LinkTotals& l);

// The kernel's laser displacement sensors' centroid (platen frame, m)
// relative to the point where it measures z, for the ccq metrics' z as the
// mean of the heights (MetricInputs): (0, 0) when that is where it measures.
void height_sensor_centroid_m(const kernel::KernelConfig& config, double out[2]);
// The platen's centre in x and y (the plant's position is its centre of
// mass, which an as-built platen carries off the centre; theta_z is urad
// where it is asked: the offset's rotation is below 1e-8 m).
void platen_centre_m(const hil::Plant& plant, double out[2]);
// homing_error_x_m / _y_m: the kernel's homed x, y on the first InPlaneLock
// tick minus the platen's centre then (in process and over CAN alike).
void add_homing_metrics(const double pose_xy_m[2], const double centre_xy_m[2], std::map<std::string, double>* M);
// Marks the actions the controller refused (commands[i] is actions[i]'s
// log: both executors log every action they run, in order).
void mark_refused_actions(const std::vector<CommandLog>& commands, std::vector<TimelineAction>* actions);
// Real-time mode: deadline misses and the wake-up lateness histogram.
void add_realtime_metrics(const can::PeriodicTimer& timer, std::map<std::string, double>* M);

// Sizes every column of the trace to n rows: before the run loop, so that
// the loop writes rows by index into memory already touched (a first touch
// of a reserved page inside the loop is a page fault there: ~1 900 of them
// for the default scenario's 7.5 MB), and after it, to the rows recorded.
void resize_rows(Trace* tr, std::size_t n);

}  // namespace maglev::bench::internal
