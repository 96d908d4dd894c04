// What every network reader does once its file is parsed, whatever the format: the length unit
// (the unit the file declares, else the caller's `length_unit` or `length_factor`, else metres),
// scaling coordinates and radii to metres, a size limit before segments are built, and the
// checks on the built network: a network in several disconnected pieces is an error naming
// them (or the inlet's piece is kept, with a warning), and radii that look like another length
// unit (largest above 5 cm or below 1 um) are warned about, naming the likely unit.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "flowire/common/diagnostics.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/units.hpp"
#include "read_internal.hpp"

namespace flowire::vessels::detail {
namespace {

/// Warn when the radii (already in metres) look like another unit.
void check_units(double r_max, double factor, const std::string& where) {
  if (!(r_max > 0.05 || (r_max > 0.0 && r_max < 1e-6))) return;
  const double raw = r_max / factor;  // in file units
  struct Cand {
    const char* name;
    double f;
  };
  std::vector<std::pair<double, const char*>> plausible;
  for (const Cand c : {Cand{"m", 1.0}, Cand{"cm", 1e-2}, Cand{"mm", 1e-3}, Cand{"um", 1e-6}}) {
    const double r = raw * c.f;
    if (r >= 1e-4 && r <= 0.05) plausible.emplace_back(std::abs(std::log10(r / 5e-3)), c.name);  // typical: 5 mm
  }
  std::sort(plausible.begin(), plausible.end());
  std::string hint = "check length_unit";
  if (!plausible.empty()) {
    hint = fmt::format("the file is probably in {}", plausible[0].second);
    if (plausible.size() > 1) hint += fmt::format(" (or {})", plausible[1].second);
    hint += fmt::format(": set length_unit: {0} (command line: --length-unit {0})", plausible[0].second);
  }
  warn(fmt::format("{}: the largest radius is {:.4g} m, not a blood vessel in the length unit used; {}", where, r_max,
                   hint));
}

/// Refuses centerlines that would build an absurd number of segments (wrong unit, corrupt
/// coordinates) before Network::build allocates them.
void check_build_size(const Centerlines& c, const BuildOptions& opt) {
  double total = 0.0;
  for (size_t b = 0; b < c.branches.size(); ++b) {
    const auto& p = c.branches[b];
    double len = 0.0;
    for (size_t i = 1; i < p.points.size(); ++i) len += (p.points[i] - p.points[i - 1]).norm();
    if (!std::isfinite(len))
      throw_input_error(c.source, fmt::format("branch {}: coordinates too large (its length is not finite)", b));
    total += static_cast<double>(p.points.size());
    if (opt.max_segment_length > 0.0) total += len / opt.max_segment_length;
  }
  if (total > 2e7)
    throw_input_error(c.source, fmt::format("cutting the branches into segments of at most {} m would make about "
                                            "{:.3g} segments; check length_unit and max_segment_length",
                                            opt.max_segment_length, total));
}

}  // namespace

std::string read_network_text(const std::string& path) {
  return read_input(path, input_limit::kGeometry, "a network file");
}

double length_factor(const ReadOptions& opt, const std::optional<std::string>& declared, const std::string& where) {
  std::optional<double> user;
  std::string user_name = opt.length_unit;
  if (opt.length_factor > 0.0) {
    if (!std::isfinite(opt.length_factor)) throw_usage_error("length factor must be finite");
    user = opt.length_factor;
    user_name = fmt::format("factor {}", opt.length_factor);
  } else if (!opt.length_unit.empty()) {
    user = units::length_unit_factor(opt.length_unit, "length unit");
  }
  if (declared) {
    const double f = units::length_unit_factor(*declared, where + ": length_unit");
    if (user && std::abs(*user - f) > 1e-12 * f)
      warn(fmt::format("{}: the file declares length_unit {}; the length unit given ({}) is ignored", where, *declared,
                       user_name));
    return f;
  }
  return user.value_or(1.0);
}

void scale(Centerlines& c, double f) {
  if (f == 1.0) return;
  for (auto& b : c.branches) {
    for (auto& p : b.points) p *= f;
    for (auto& r : b.radii) r *= f;
  }
}

Network build_checked(const Centerlines& c, const BuildOptions& opt) {
  check_build_size(c, opt);
  return Network::build(c, opt);
}

Network finish(Network net, const ReadOptions& opt, double factor, const std::string& path) {
  int pieces = 0;
  const auto comp = net.components(&pieces);
  if (pieces > 1) {
    if (opt.keep_inlet_piece) {
      const int inlet = net.widest_end();
      const int keep = inlet >= 0 ? inlet : 0;
      const int kept = comp[static_cast<size_t>(keep)];
      int dropped_segments = 0;
      for (const auto& s : net.segments())
        if (comp[static_cast<size_t>(s.node_from)] != kept) ++dropped_segments;
      warn(
          fmt::format("{}: the network has {} disconnected pieces; kept the piece with the widest end (node {}) and "
                      "dropped {} segment(s) of the others",
                      path, pieces, keep, dropped_segments));
      net = net.keep_component(keep);
    } else {
      std::vector<std::vector<std::string>> names(static_cast<size_t>(pieces));
      std::vector<int> seg_count(static_cast<size_t>(pieces), 0);
      for (const auto& s : net.segments()) ++seg_count[static_cast<size_t>(comp[static_cast<size_t>(s.node_from)])];
      for (const auto& b : net.branches())
        if (!b.nodes.empty()) names[static_cast<size_t>(comp[static_cast<size_t>(b.nodes.front())])].push_back(b.name);
      std::string list;
      for (size_t k = 0; k < names.size(); ++k) {
        std::string bn;
        for (size_t i = 0; i < names[k].size() && i < 4; ++i) bn += (i ? ", " : "") + names[k][i];
        if (names[k].size() > 4) bn += fmt::format(", ... ({} branches)", names[k].size());
        list += fmt::format("{}piece {}: {} segment(s), branches {}", k ? "; " : "", k + 1, seg_count[k], bn);
      }
      throw_input_error(path, fmt::format("the network is in {} disconnected pieces ({}); join them in the file, or "
                                          "keep only the piece of the inlet (keep_inlet_piece)",
                                          pieces, list));
    }
  }
  if (opt.check_units) check_units(net.counts().radius_max, factor, path);
  return net;
}

}  // namespace flowire::vessels::detail
