// flowire_bench: run time against error, per-frame cost, feature cost and the stability
// stress matrix. Every subcommand writes a CSV that the plotting scripts read.
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "studies.hpp"

#ifndef FLOWIRE_SOURCE_DIR
#define FLOWIRE_SOURCE_DIR "."
#endif

namespace flowire::bench {

void emit(const Options& o, const std::string& name, const std::string& text) {
  std::filesystem::create_directories(o.out_dir);
  const auto path = std::filesystem::path(o.out_dir) / name;
  std::ofstream f(path);
  f << text;
  std::cout << text << std::flush;
  std::cerr << "flowire_bench: wrote " << path.string() << "\n";
}

}  // namespace flowire::bench

namespace {

int usage() {
  std::fputs(
      "usage: flowire_bench COMMAND [--out DIR] [--reduced] [--scene FILE] [--known FILE] [--only TEXT]...\n"
      "commands:\n"
      "  rod-work-precision    cantilever/buckling error and frequency error vs run time; step cost vs n\n"
      "  flow-frame-cost       dense_inverse vs superposition vs sparse per frame; rlc vs Womersley vs dt\n"
      "  flow-fem-work-precision  network and FEM outlet-flow error vs run time (built with FLOWIRE_WITH_FEM)\n"
      "  cosim-work-precision  aortic-arch tip-trace error vs run time over dt and segment length\n"
      "  feature-cost          per-phase timings with each feature switched off\n"
      "  stress                the stability matrix (pass/fail CSV)\n"
      "  all                   every one of the above\n",
      stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace flowire::bench;
  if (argc < 2) return usage();
  const std::string cmd = argv[1];
  Options o;
  o.scene = std::string(FLOWIRE_SOURCE_DIR) + "/examples/aortic_arch/scene.yaml";
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--reduced" || a == "--quick")
      o.reduced = true;
    else if (a == "--out" && i + 1 < argc)
      o.out_dir = argv[++i];
    else if (a == "--scene" && i + 1 < argc)
      o.scene = argv[++i];
    else if (a == "--known" && i + 1 < argc)
      o.known_failures = argv[++i];
    else if (a == "--only" && i + 1 < argc)
      o.only.emplace_back(argv[++i]);
    else
      return usage();
  }
  try {
    if (cmd == "rod-work-precision") return rod_work_precision(o);
    if (cmd == "flow-frame-cost") return flow_frame_cost(o);
    if (cmd == "flow-fem-work-precision") {
#ifdef FLOWIRE_BENCH_FEM
      return flow_fem_work_precision(o);
#else
      std::cerr << "flowire_bench: flow-fem-work-precision needs a build with FLOWIRE_WITH_FEM=ON\n";
      return 2;
#endif
    }
    if (cmd == "cosim-work-precision") return cosim_work_precision(o);
    if (cmd == "feature-cost") return feature_cost(o);
    if (cmd == "stress") return stress(o);
    if (cmd == "all") {
      int rc = 0;
      for (auto f : {rod_work_precision, flow_frame_cost, cosim_work_precision, feature_cost, stress}) rc |= f(o);
      return rc;
    }
  } catch (const std::exception& e) {
    std::cerr << "flowire_bench: error: " << e.what() << "\n";
    return 3;
  }
  return usage();
}
