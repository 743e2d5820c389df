// Results writers of the HIL bench: metrics.json (flat name -> number, SI
// units in the names), trace.csv (time series), the terminal table (each
// metric beside the paper's figure) and the PNG plots (plot_run.py, Debian's
// python3-matplotlib, invoked as /usr/bin/python3).
#pragma once

#include <map>
#include <string>

#include "maglev/bench/runner.hpp"

namespace maglev::report {

bool write_metrics_json(const bench::RunResult& r, const std::string& path, std::string* error);
// Columns: t_s, x_m y_m z_m theta_x_rad theta_y_rad theta_z_rad, the six
// *_ref_*, i1_cmd_A..i8_cmd_A, i1_A..i8_A, state (SequencerState number).
bool write_trace_csv(const bench::Trace& t, const std::string& path, std::string* error);
// The band a figure reproducing the paper's measured stage must lie in, as a
// ratio measured / paper (issue 15): the table's verdicts and the `--seeds`
// summary both use it. Loop figures use their own 20 % (report.cpp).
inline constexpr double kPaperBandLow = 0.5, kPaperBandHigh = 2.0;
// The table: metric | measured | paper (where [paper] names it).
std::string format_table(const bench::RunResult& r);
// Writes DIR/metrics.json, DIR/trace.csv, DIR/commands.txt and the plots.
// primary: pose axis name for the figure's large panel.
bool write_run(const bench::RunResult& r, const std::string& dir, const std::string& primary, bool plots,
               std::string* error);
// Runs the plot script; false (with *error) if python3-matplotlib is missing.
bool make_plots(const std::string& dir, const std::string& primary, const std::string& title, std::string* error);

}  // namespace maglev::report
