// cosim-work-precision and feature-cost: the aortic-arch scene through coupling::run_scene.
#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/coupling/scene.hpp"
#include "flowire/coupling/trace_compare.hpp"
#include "studies.hpp"

namespace flowire::bench {

namespace {

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// The scene text without one top-level section (e.g. "flow"): lines from `name:` up to the
/// next top-level key. A scene without `flow:` builds no flow solver at all.
std::string without_section(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  std::string line, out;
  bool skipping = false;
  while (std::getline(in, line)) {
    const bool top = !line.empty() && line[0] != ' ' && line[0] != '#';
    if (top) skipping = line.rfind(name + ":", 0) == 0;
    if (!skipping) out += line + "\n";
  }
  return out;
}

nlohmann::json run(const std::string& text, const std::string& name, std::vector<std::string> sets) {
  const auto cfg = config::load_config_text(text, name, coupling::scene_schema(), sets);
  auto r = coupling::run_scene(cfg);
  (void)take_warnings();
  return r.summary;
}

}  // namespace

int cosim_work_precision(const Options& o) {
  const std::string text = read_text(o.scene);
  const double duration = o.reduced ? 3.0 : 12.0;
  const std::string dir = (std::filesystem::path(o.out_dir) / "cosim_runs").string();
  auto sets_for = [&](double dt, double seg, const std::string& tag) {
    return std::vector<std::string>{fmt::format("solve.dt={:.9g}", dt),
                                    fmt::format("solve.duration={:.9g}", duration),
                                    fmt::format("wire.segment_length={:.9g}", seg),
                                    "output.vtk=false",
                                    "output.csv=true",
                                    "output.every=0",
                                    "output.dir=" + dir + "/" + tag};
  };
  // Reference: finest dt and segment length of the study.
  const double ref_dt = o.reduced ? 2.5e-3 : 1e-3, ref_seg = o.reduced ? 1e-3 : 0.5e-3;
  const auto ref_summary = run(text, o.scene, sets_for(ref_dt, ref_seg, "reference"));
  const auto ref = coupling::read_tip_trace(dir + "/reference/tip_trace.csv");
  std::string csv =
      "dt,segment_length,rms_error,max_error,rms_published,seconds,rod_seconds,steps,status,unconverged_steps\n";
  csv += fmt::format("{:g},{:g},0,0,0,{:.6e},{:.6e},{},{},{}\n", ref_dt, ref_seg,
                     ref_summary["timings"]["total"].get<double>(), ref_summary["timings"]["rod"].get<double>(),
                     ref_summary["steps"].get<long>(), ref_summary["status"].get<std::string>(),
                     ref_summary["wire"]["unconverged_steps"].get<int>());
  const std::vector<double> dts =
      o.reduced ? std::vector<double>{20e-3, 10e-3} : std::vector<double>{40e-3, 20e-3, 10e-3, 5e-3, 2.5e-3};
  const std::vector<double> segs = o.reduced ? std::vector<double>{4e-3, 2e-3} : std::vector<double>{4e-3, 2e-3, 1e-3};
  for (double seg : segs)
    for (double dt : dts) {
      const std::string tag = fmt::format("dt{:g}ms_seg{:g}mm", dt * 1e3, seg * 1e3);
      const auto s = run(text, o.scene, sets_for(dt, seg, tag));
      const auto tr = coupling::read_tip_trace(dir + "/" + tag + "/tip_trace.csv");
      const auto cmp = coupling::compare_traces(tr, ref, 5e-3, 50e-3);
      double maxd = 0.0;
      for (const auto& row : cmp.rows) maxd = std::max(maxd, row.max_distance);
      csv += fmt::format("{:g},{:g},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}\n", dt, seg, cmp.rms_total, maxd,
                         cmp.rms_published_total, s["timings"]["total"].get<double>(),
                         s["timings"]["rod"].get<double>(), s["steps"].get<long>(), s["status"].get<std::string>(),
                         s["wire"]["unconverged_steps"].get<int>());
    }
  emit(o, "cosim_work_precision.csv", csv);
  return 0;
}

int feature_cost(const Options& o) {
  const std::string text = read_text(o.scene);
  const double duration = o.reduced ? 2.0 : 10.0;
  const std::string dir = (std::filesystem::path(o.out_dir) / "feature_runs").string();
  struct Variant {
    std::string name, text;
    std::vector<std::string> sets;
  };
  const std::vector<std::string> common = {fmt::format("solve.duration={:g}", duration), "output.every=0.5"};
  std::vector<Variant> variants = {
      {"all_on", text, {}},
      {"flow_off", without_section(text, "flow"), {}},
      {"drag_off", text, {"coupling.drag=none"}},
      {"friction_off", text, {"contact.friction=0", "contact.tip_friction=0"}},
      {"output_off", text, {"output.csv=false", "output.vtk=false"}},
      // Without contact the wire leaves the lumen (accepted here: the row measures cost); the
      // lookup stays for the drag.
      {"contact_off", text, {"contact.enabled=false", "contact.allow_outside=true"}},
      {"contact_and_drag_off", text, {"contact.enabled=false", "coupling.drag=none", "contact.allow_outside=true"}},
      // Adaptivity is off in the scene (its cost is then nil: no resampling is attempted);
      // this row shows what it costs when on.
      {"adapt_on", text, {"wire.adapt.split_angle=0.1"}},
  };
  std::string csv =
      "variant,setup,flow,rod,contact,coupling,output,total,steps,status,flow_frames,window_hits,fallbacks,"
      "newton_per_step\n";
  for (auto& v : variants) {
    auto sets = common;
    sets.insert(sets.end(), v.sets.begin(), v.sets.end());
    sets.push_back("output.dir=" + dir + "/" + v.name);
    const auto s = run(v.text, o.scene, sets);
    const auto& t = s["timings"];
    const long frames = s.contains("flow") && s["flow"].contains("frames") ? s["flow"]["frames"].get<long>() : 0L;
    const long hits = s.contains("lookup") ? s["lookup"]["window_hits"].get<long>() : 0L;
    const long falls = s.contains("lookup") ? s["lookup"]["fallbacks"].get<long>() : 0L;
    const double newton = s["wire"]["solver"]["newton_iterations_per_step"].get<double>();
    csv += fmt::format("{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{},{},{},{:.3f}\n", v.name,
                       t["setup"].get<double>(), t["flow"].get<double>(), t["rod"].get<double>(),
                       t["contact"].get<double>(), t["coupling"].get<double>(), t["output"].get<double>(),
                       t["total"].get<double>(), s["steps"].get<long>(), s["status"].get<std::string>(), frames, hits,
                       falls, newton);
  }
  emit(o, "feature_cost.csv", csv);
  return 0;
}

int stress(const Options& o);

}  // namespace flowire::bench
