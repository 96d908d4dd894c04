// The flowire command line (contract: ../shared/contract/flowire-cli.md).
// Exit status: 0 success; 2 bad usage or bad input; 3 numerical failure.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <new>
#include <nlohmann/json.hpp>

#include "dispatch.hpp"
#include "fit_command.hpp"
#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/output.hpp"
#include "flowire/common/units.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/trace_compare.hpp"
#include "flowire/vessels/io.hpp"
#include "programs.hpp"
#include "run_command.hpp"
#include "study_command.hpp"
#include "study_file.hpp"

namespace {

using flowire::Error;
using flowire::ErrorKind;
using flowire::cli::error_exit;
using flowire::cli::launcher_rank;
using flowire::cli::print_warnings;

flowire::vessels::ReadOptions read_options(const std::string& unit, double max_seg) {
  flowire::vessels::ReadOptions ro;
  ro.length_unit = unit;
  if (max_seg > 0) ro.build.max_segment_length = max_seg;
  return ro;
}

int cmd_calibrate(const std::string& scene, const std::string& out, const std::vector<std::string>& sets,
                  const std::vector<double>& factors, double check) {
  if (launcher_rank() != 0) flowire::set_writes_outputs(false);
  flowire::check_input_file(scene, flowire::input_limit::kScene, "a scene (YAML)");
  const auto cfg = flowire::coupling::load_scene(scene, sets, out);
  flowire::coupling::CalibrateOptions options;
  if (!factors.empty()) options.factors = factors;
  options.check_factor = check;
  const auto s = flowire::coupling::calibrate_scene(cfg, options);
  print_warnings();
  if (!flowire::writes_outputs()) return 0;
  std::printf("flowire: calibrate %s: ok in %.3f s, %zu 3D solutions; %s/calibration.json, calibration.md\n",
              scene.c_str(), s["timings"].value("total", 0.0), s["calibration"]["runs"].size(),
              cfg.string("output.dir").c_str());
  return 0;
}

int cmd_info(const std::string& file, const std::string& unit, double max_seg, bool json) {
  const auto net = flowire::vessels::read_network(file, read_options(unit, max_seg));
  const auto n = net.counts();
  print_warnings();
  if (json) {
    nlohmann::json j = flowire::coupling::counts_json(n);
    j["file"] = file;
    j["inlet_node"] = net.widest_end();
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("file:          %s\n", file.c_str());
    std::printf("branches:      %d\nnodes:         %d\nsegments:      %d\njunctions:     %d\nends:          %d\n",
                n.branches, n.nodes, n.segments, n.junctions, n.ends);
    std::printf("loops:         %d\ncomponents:    %d\n", n.loops, n.components);
    std::printf("total length:  %.6g m\nradius:        %.6g .. %.6g m\ninlet (widest end): node %d\n", n.total_length,
                n.radius_min, n.radius_max, net.widest_end());
  }
  return 0;
}

int cmd_convert(const std::string& in, const std::string& out, const std::string& unit, double max_seg) {
  const auto net = flowire::vessels::read_network(in, read_options(unit, max_seg));
  flowire::vessels::write_network(net, out);
  print_warnings();
  const auto n = net.counts();
  std::printf("flowire: wrote %s (%d branches, %d segments)\n", out.c_str(), n.branches, n.segments);
  return 0;
}

/// The plotting script: next to an installed flowire, or in the source tree of a build.
std::filesystem::path plot_script() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("FLOWIRE_DATA_DIR")) return fs::path(env) / "plot_traces.py";
  const fs::path installed = fs::path(FLOWIRE_INSTALL_DATADIR) / "plot_traces.py";
  if (fs::exists(installed)) return installed;
  return fs::path(FLOWIRE_SOURCE_DATADIR) / "plot_traces.py";
}

void plot_compare(const std::string& a, const std::string& b, const std::string& csv_path, const std::string& png) {
  const auto script = plot_script();
  if (!std::filesystem::exists(script))
    throw flowire::Error(ErrorKind::Input, fmt::format("--plot: the plotting script {} is missing", script.string()));
  flowire::write_atomically(png, [&](const std::filesystem::path& tmp) {
    const std::string cmd = fmt::format("/usr/bin/python3 '{}' '{}' 'A={}' 'B={}' --compare '{}' >/dev/null 2>&1",
                                        script.string(), tmp.string(), a, b, csv_path);
    if (std::system(cmd.c_str()) != 0 || !std::filesystem::exists(tmp))
      throw flowire::Error(
          ErrorKind::Input,
          fmt::format("--plot {}: plotting failed (needs /usr/bin/python3 with python3-matplotlib)", png));
  });
}

int cmd_compare(const std::string& a, const std::string& b, const std::string& out, const std::string& spacing,
                const std::string& row, const std::string& plot) {
  using flowire::units::Dimension;
  const double h = flowire::units::parse_quantity(spacing, Dimension::Length, "--spacing");
  const double H = flowire::units::parse_quantity(row, Dimension::Length, "--rows");
  const auto r = flowire::coupling::compare_traces(flowire::coupling::read_tip_trace(a),
                                                   flowire::coupling::read_tip_trace(b), h, H);
  if (r.samples == 0)
    throw flowire::Error(ErrorKind::Input, fmt::format("{} and {}: the traces share no inserted length", a, b));
  const auto csv = flowire::coupling::compare_csv(r);
  if (!out.empty()) flowire::write_text_atomically(out, csv);
  if (!plot.empty()) {
    const std::string table = out.empty() ? plot + ".csv" : out;
    if (out.empty()) flowire::write_text_atomically(table, csv);
    plot_compare(a, b, table, plot);
  }
  std::printf("%-18s %8s %22s %14s %14s\n", "inserted length mm", "samples", "RMS (1/2 sum)^1/2 mm", "RMS mean mm",
              "max mm");
  for (const auto& row_ : r.rows)
    std::printf("%18.1f %8d %22.3f %14.3f %14.3f\n", row_.inserted_length * 1e3, row_.samples, row_.rms_published * 1e3,
                row_.rms * 1e3, row_.max_distance * 1e3);
  std::printf("%18s %8d %22.3f %14.3f\n", "all", r.samples, r.rms_published_total * 1e3, r.rms_total * 1e3);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  flowire::install_interrupt_handlers();
  flowire::cli::follow_parent();  // a run of a study or a fit ends with the study
  CLI::App app{"flowire: guidewire and blood-flow co-simulation in vessel networks", "flowire"};
  app.set_version_flag("--version", std::string("flowire ") + FLOWIRE_VERSION);
  app.require_subcommand(0, 1);
  app.set_help_all_flag("--help-all", "help for every command");

  flowire::cli::RunArgs run_args;
  auto* run = flowire::cli::add_run_command(app, run_args);

  auto* network = app.add_subcommand("network", "read, inspect and convert vessel networks");
  network->require_subcommand(1);
  std::string file, unit, in, outfile;
  double max_seg = 0;
  bool json = false;
  auto* info =
      network->add_subcommand("info", "print branches, nodes, segments, junctions, ends, loops, length, radii");
  info->add_option("file", file, "network file (" + flowire::vessels::network_extensions() + ")")->required();
  info->add_option("--length-unit", unit, "unit of the file's coordinates: m, cm, mm, um");
  info->add_option("--max-segment-length", max_seg, "split branches into segments no longer than this (m)");
  info->add_flag("--json", json, "print one JSON object");
  auto* convert = network->add_subcommand("convert", "convert a network file (to .vtp or .yaml)");
  convert->add_option("in", in, "input network file")->required();
  convert->add_option("out", outfile, "output file (.vtp or .yaml)")->required();
  convert->add_option("--length-unit", unit, "unit of the input's coordinates: m, cm, mm, um");
  convert->add_option("--max-segment-length", max_seg, "split branches into segments no longer than this (m)");

  std::string ta, tb, cmp_out, cmp_plot, spacing = "5 mm", rows = "50 mm";
  auto* compare = app.add_subcommand("compare", "RMS distance between two tip traces by inserted length");
  compare->add_option("a", ta, "tip_trace.csv")->required();
  compare->add_option("b", tb, "tip_trace.csv")->required();
  compare->add_option("--out", cmp_out, "write the table as CSV");
  compare->add_option("--plot", cmp_plot, "draw both traces and the RMS by inserted length to a PNG");
  compare->add_option("--spacing", spacing, "sample spacing of inserted length (default 5 mm)");
  compare->add_option("--rows", rows, "table row spacing (default 50 mm)");

  flowire::cli::FitOptions fit_opts;
  auto* fit =
      app.add_subcommand("fit", "fit scene values to a measured tip trace (CMA-ES on the trace RMS; docs/fit.md)");
  fit->add_option("scene", fit_opts.scene, "scene file (.yaml)")->required();
  fit->add_option("--trace", fit_opts.trace, "measured tip trace (tip_trace.csv columns: time,inserted_length,x,y,z)")
      ->required();
  fit->add_option("--param", fit_opts.params,
                  "a scene value to fit and its range, units as the scene accepts them: "
                  "--param insertion.rotation_angle=0deg..180deg (repeatable)")
      ->required()
      ->allow_extra_args(false);
  fit->add_option("--out", fit_opts.out, "output folder: fit.json, fit_history.csv and the best run's outputs")
      ->required();
  fit->add_option("--set", fit_opts.sets, "fix a scene key for every run: --set solve.dt=5ms (repeatable)")
      ->allow_extra_args(false);
  fit->add_option("--jobs", fit_opts.jobs, "runs at a time (default: the number of hardware threads)")
      ->check(CLI::NonNegativeNumber);
  fit->add_option("--max-evaluations", fit_opts.max_evaluations, "stop after this many runs (default 100*(params+1))")
      ->check(CLI::NonNegativeNumber);
  fit->add_option("--seed", fit_opts.seed, "random seed of the search (equal seeds give equal fits; default 1)");

  std::string cal_scene, cal_out;
  std::vector<std::string> cal_sets;
  std::vector<double> cal_factors;
  double cal_check = 0.75;
  auto* calibrate = app.add_subcommand(
      "calibrate",
      "fit the network's segments to the 3D solution of the scene's fem: section (docs/fem-real-lumens.md)");
  calibrate->add_option("scene", cal_scene, "scene file (.yaml) with vessels:, flow: and fem: sections")->required();
  calibrate->add_option("--out", cal_out, "output folder (overrides output.dir): calibration.json, calibration.md");
  calibrate->add_option("--set", cal_sets, "override a scene key: --set fem.size_factor=0.4 (repeatable)")
      ->allow_extra_args(false);
  calibrate
      ->add_option("--flows", cal_factors,
                   "the scene's inlet value times these factors are the 3D solutions fitted (default 0.5 1 1.5)")
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  calibrate->add_option("--check", cal_check, "one more solution at this factor, not fitted (default 0.75; 0: none)")
      ->check(CLI::NonNegativeNumber);

  flowire::cli::StudyOptions study_opts;
  auto* study = app.add_subcommand(
      "study", "run a study: cases x a product of scene values, collected into tables and plots (docs/study.md)");
  study->add_option("study", study_opts.file, "study file (.yaml; flowire help study lists its keys)")->required();
  study->add_option("--out", study_opts.out, "output folder: study.csv, timings.csv, pairs.csv, plots/, runs/");
  study
      ->add_option("--jobs", study_opts.jobs,
                   "runs at a time on each rank (default: the hardware threads; 1 per rank under mpirun)")
      ->check(CLI::NonNegativeNumber);
  study->add_flag("--list", study_opts.list, "check the study and print its runs; nothing is run or written");

  std::vector<std::string> help_topic;
  auto* help = app.add_subcommand("help", "help for a command; `help scene` lists every scene key");
  help->add_option("command", help_topic, "command (run, network, compare, fit, study, scene)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return error_exit(e.what(), 2);
  }

  try {
    if (*run) return flowire::cli::cmd_run(run_args);
    if (*info) return cmd_info(file, unit, max_seg, json);
    if (*convert) return cmd_convert(in, outfile, unit, max_seg);
    if (*compare) return cmd_compare(ta, tb, cmp_out, spacing, rows, cmp_plot);
    if (*fit) return flowire::cli::run_fit(fit_opts);
    if (*calibrate) return cmd_calibrate(cal_scene, cal_out, cal_sets, cal_factors, cal_check);
    if (*study) return flowire::cli::run_study(study_opts);
    if (*help) {
      if (help_topic.empty()) {
        std::cout << app.help();
      } else if (help_topic[0] == "scene") {
        std::cout << "Scene keys (SI units; \"<number> <unit>\" strings accepted):\n\n"
                  << flowire::coupling::scene_schema().markdown();
      } else if (help_topic[0] == "study") {
        std::cout << app.get_subcommand("study")->help() << "\nStudy file keys (docs/study.md):\n\n"
                  << flowire::cli::study_keys_markdown();
      } else if (help_topic[0] == "run" || help_topic[0] == "network" || help_topic[0] == "compare" ||
                 help_topic[0] == "fit" || help_topic[0] == "calibrate") {
        std::cout << app.get_subcommand(help_topic[0])->help();
      } else {
        return error_exit(
            fmt::format(
                "help: unknown command '{}' (commands: run, network, compare, fit, calibrate, study, help scene)",
                help_topic[0]),
            2);
      }
      return 0;
    }
    std::cout << app.help();
    return 0;
  } catch (const Error& e) {
    print_warnings();
    return error_exit(e.what(), flowire::exit_status(e));
  } catch (const std::bad_alloc&) {
    return error_exit("out of memory", 3);
  } catch (const std::exception& e) {
    return error_exit(fmt::format("unexpected failure: {}", e.what()), 3);
  }
}
