// flowire_bench stress: the matrix as a pass/fail CSV; exit status 1 if any point fails.
#include <fmt/format.h>

#include <fstream>
#include <iostream>
#include <set>
#include <stdexcept>
#include <string>

#include "stress.hpp"
#include "studies.hpp"

namespace flowire::bench {

namespace {

/// Ids of known failures: the first field (up to a space or tab) of every non-empty line that
/// does not start with '#'; the rest of the line is the explanation.
std::set<std::string> read_known(const std::string& path) {
  std::set<std::string> ids;
  if (path.empty()) return ids;
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read known-failures file " + path);
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    ids.insert(line.substr(0, line.find_first_of(" \t")));
  }
  return ids;
}

}  // namespace

int stress(const Options& o) {
  const auto known = read_known(o.known_failures);
  std::set<std::string> failed;
  auto matrix = stress_matrix(o.reduced);
  // --only: keep the points whose id contains every given fragment (e.g. "mu=1," "dt=1ms").
  std::erase_if(matrix, [&](const StressPoint& p) {
    const std::string id = stress_point_id(p);
    for (const auto& f : o.only)
      if (id.find(f) == std::string::npos) return true;
    return false;
  });
  std::string csv = stress_csv_header();
  int passed = 0, stalled = 0;
  std::string failures;
  for (size_t i = 0; i < matrix.size(); ++i) {
    const auto r = run_stress_point(o.scene, matrix[i]);
    csv += stress_csv_row(r);
    passed += r.pass ? 1 : 0;
    stalled += r.stalled() ? 1 : 0;
    std::cerr << fmt::format("stress {}/{} {} {} {:.2f}s, fed {:.3g} of {:.3g} m{}{}\n", i + 1, matrix.size(),
                             r.pass ? "pass" : "FAIL", stress_point_id(r.point), r.seconds, r.fed, r.planned_feed,
                             r.stalled() ? " (held by the force limit: tests a held wire)" : "",
                             r.pass ? "" : fmt::format(" step {}: {}", r.first_bad_step, r.reason));
    if (!r.pass) failed.insert(stress_point_id(r.point));
    if (!r.pass) failures += fmt::format("  {}: step {}: {}\n", stress_point_id(r.point), r.first_bad_step, r.reason);
  }
  emit(o, "stress.csv", csv);
  std::cerr << fmt::format("stress: {}/{} passed ({:.1f}%)\n{}", passed, matrix.size(),
                           100.0 * passed / static_cast<double>(matrix.size()), failures);
  if (stalled > 0)
    std::cerr << fmt::format(
        "stress: {} of {} points fed less than half of their planned length (the {} N force limit held them): "
        "they pass as held wires, not as fed ones (column stalled of stress.csv)\n",
        stalled, matrix.size(), 2);
  if (o.known_failures.empty()) return passed == static_cast<int>(matrix.size()) ? 0 : 1;
  // With a known-failures list: succeed only if the failures are exactly the listed ones
  // (of the points this matrix ran).
  bool same = true;
  for (const auto& id : failed)
    if (!known.count(id)) {
      std::cerr << "stress: new failure " << id << "\n";
      same = false;
    }
  for (const auto& p : matrix)
    if (known.count(stress_point_id(p)) && !failed.count(stress_point_id(p))) {
      std::cerr << "stress: listed as known but passes now (update the list) " << stress_point_id(p) << "\n";
      same = false;
    }
  return same ? 0 : 1;
}

}  // namespace flowire::bench
