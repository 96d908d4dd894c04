// The study file: one declaration of its keys (what `flowire help study` and docs/study.md
// show, and what the reader accepts), the reader that checks every key, value and scene
// before anything runs, and the expansion into runs (cases × the product of the parameters).
#include "study_file.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <regex>
#include <set>

#include "flowire/common/config.hpp"
#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"
#include "flowire/common/units.hpp"
#include "flowire/coupling/scene.hpp"

namespace flowire::cli {
namespace {

namespace fs = std::filesystem;

constexpr YAML::NodeType::value kAbsent = YAML::NodeType::Undefined;

/// One declared key of the study file. A path segment in angle brackets stands for any name.
struct StudyKey {
  std::string path, type, default_text, doc;
};

const std::vector<StudyKey>& study_keys() {
  static const std::vector<StudyKey> keys = {
      {"scene", "file", "", "the base scene (YAML), relative to the study file; required unless every case names one"},
      {"set", "map", "",
       "scene keys fixed for every run, each as `--set` takes it: `{solve.dt: 5 ms, output.vtk: false}`"},
      {"set.<scene key>", "value", "", "a value as the scene accepts it (units as in a scene, lists as `[1, 0, 0]`)"},
      {"parameters", "map", "",
       "the scene keys the study varies; their values are combined as a product, the first key varying slowest"},
      {"parameters.<scene key>", "list \\| range", "",
       "the values as the scene accepts them (`[1 cm/s, 2 cm/s]`, `[cylinder, none]`), or a linear range"},
      {"parameters.<scene key>.from", "value", "",
       "range: the first value (a number key; units as the scene accepts them)"},
      {"parameters.<scene key>.to", "value", "", "range: the last value"},
      {"parameters.<scene key>.count", "integer", "", "range: how many evenly spaced values (at least 2)"},
      {"zip", "list of lists", "",
       "groups of parameters that vary together, `[[insertion.speed, solve.duration]]`: a group is one axis of the "
       "product, at its first member's place; its lists have equal lengths"},
      {"cases", "map", "",
       "named cases: the whole product is run for each (the case is the outermost loop), e.g. one per anatomy"},
      {"cases.<name>", "map", "", "a case, named by letters, digits, `_`, `-`, `.`; empty: the base scene as it is"},
      {"cases.<name>.scene", "file", "`scene`", "the case's scene, relative to the study file"},
      {"cases.<name>.set", "map", "", "scene keys fixed for the case's runs (applied after `set`)"},
      {"collect", "map", "", "what each run yields, by name (letters, digits, `_`): one column of study.csv each"},
      {"collect.<name>", "map", "", "one quantity: exactly one of `summary`, `tip`, `clamp_force`"},
      {"collect.<name>.summary", "text", "",
       "a summary.json value by its dotted path, list items as `[i]`: `wire.inserted_length`, `status`, "
       "`wire.unconverged_steps`, `wire.tip[2]` (quoted inside `{...}`); `timings.*` values go to timings.csv"},
      {"collect.<name>.tip", "final_position \\| time_to_length", "",
       "from tip_trace.csv: the last tip position (columns NAME_x, NAME_y, NAME_z, m) or the first time the "
       "inserted length reaches `length` (s, interpolated; empty if it never does)"},
      {"collect.<name>.length", "length", "", "`tip: time_to_length`: the inserted length to reach"},
      {"collect.<name>.clamp_force", "max \\| final", "",
       "from base_force.csv: the largest or the last magnitude of the clamp's force on the wire (N)"},
      {"pairs", "map", "",
       "RMS distances between the tip traces of paired runs (pairs.csv; the published eq. 11, as `flowire compare`), "
       "by name"},
      {"pairs.<name>", "map", "", "one pairing"},
      {"pairs.<name>.parameter", "parameter", "", "the parameter that tells the two runs of a pair apart"},
      {"pairs.<name>.reference", "value", "",
       "one of its values: every run with another value is compared with the run that has this one and the same "
       "case and other values"},
      {"pairs.<name>.spacing", "length", "`5 mm`", "the inserted-length spacing of the compared samples"},
      {"keep_runs", "true \\| false \\| failed", "`true`",
       "keep each run's outputs in runs/ID/ (false: only its result.json; failed: the outputs of runs that did "
       "not end ok)"},
      {"plot", "bool", "`true`", "draw one PNG per quantity against each parameter (plots/; needs python3-matplotlib)"},
  };
  return keys;
}

std::string_view parent_of(std::string_view path) {
  const auto dot = path.rfind('.');
  return dot == std::string_view::npos ? std::string_view() : path.substr(0, dot);
}

std::string_view leaf_of(std::string_view path) {
  const auto dot = path.rfind('.');
  return dot == std::string_view::npos ? path : path.substr(dot + 1);
}

/// The declared children of @p parent ("" the top level), by their leaf names.
std::vector<std::string> declared_children(std::string_view parent) {
  std::vector<std::string> out;
  for (const auto& k : study_keys())
    if (parent_of(k.path) == parent) out.emplace_back(leaf_of(k.path));
  return out;
}

/// The scene sections summary.json has, and whether a run of a scene writes each.
struct SummarySection {
  const char* name;
  std::function<bool(const config::Config&)> written;
};

bool in_vessels_with_wire(const config::Config& c) { return c.has_section("wire") && c.has_section("vessels"); }

const std::vector<SummarySection>& summary_sections() {
  static const std::vector<SummarySection> sections = {
      {"status", [](const config::Config&) { return true; }},
      {"steps", [](const config::Config&) { return true; }},
      {"timings", [](const config::Config&) { return true; }},
      {"warnings", [](const config::Config&) { return true; }},
      {"calls", [](const config::Config&) { return true; }},
      {"scene", [](const config::Config&) { return true; }},
      {"name", [](const config::Config& c) { return c.has("name"); }},
      {"network", [](const config::Config& c) { return c.has_section("vessels"); }},
      {"surface", [](const config::Config& c) { return c.has("vessels.surface"); }},
      {"flow", [](const config::Config& c) { return c.has_section("flow"); }},
      {"fem", [](const config::Config& c) { return c.has_section("fem"); }},
      {"wire", [](const config::Config& c) { return c.has_section("wire"); }},
      {"wire_entry_node", [](const config::Config& c) { return in_vessels_with_wire(c); }},
      {"catheter", [](const config::Config& c) { return c.has_section("catheter"); }},
      {"tip_forces", [](const config::Config& c) { return c.has_section("wire"); }},
      {"lookup",
       [](const config::Config& c) {
         return in_vessels_with_wire(c) && (!c.has("contact.enabled") || c.boolean("contact.enabled"));
       }},
      {"contact",
       [](const config::Config& c) {
         return in_vessels_with_wire(c) && (!c.has("contact.enabled") || c.boolean("contact.enabled"));
       }},
      {"occlusion", [](const config::Config& c) { return in_vessels_with_wire(c) && c.has_section("flow"); }},
      {"drag",
       [](const config::Config& c) {
         return in_vessels_with_wire(c) && c.has_section("flow") &&
                !(c.has("coupling.drag") && c.string("coupling.drag") == "none");
       }},
  };
  return sections;
}

/// The reader of one study file: every message names the file, the line and the key.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[nodiscard]] std::string where(const YAML::Node& n) const {
    if (n.Mark().is_null() || n.Mark().line < 0) return file_;
    return fmt::format("{}:{}", file_, n.Mark().line + 1);
  }

  [[noreturn]] void fail(const YAML::Node& n, std::string_view key, std::string_view what) const {
    throw_input_error(where(n), key.empty() ? std::string(what) : fmt::format("{}: {}", key, what));
  }

  /// Every key of the map @p node (declared path @p decl, concrete path @p concrete) is declared
  /// and given once. Returns its entries in the file's order.
  std::vector<std::pair<YAML::Node, YAML::Node>> entries(const YAML::Node& node, const std::string& decl,
                                                         const std::string& concrete) const {
    if (!node.IsMap()) fail(node, concrete, fmt::format("expected a map, got {}", kind(node)));
    const auto children = declared_children(decl);
    const bool any = std::any_of(children.begin(), children.end(), [](const std::string& c) { return c[0] == '<'; });
    std::set<std::string> seen;
    std::vector<std::pair<YAML::Node, YAML::Node>> out;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar()) fail(kv.first, concrete, "a key must be a name, not a list or a map");
      const std::string k = kv.first.Scalar();
      const std::string path = concrete.empty() ? k : concrete + "." + k;
      if (!any && std::find(children.begin(), children.end(), k) == children.end()) {
        std::string allowed;
        for (const auto& c : children) allowed += (allowed.empty() ? "" : ", ") + c;
        fail(kv.first, "", fmt::format("unknown key '{}' (allowed here: {})", path, allowed));
      }
      if (!seen.insert(k).second) fail(kv.first, path, "given twice");
      out.emplace_back(kv.first, kv.second);
    }
    return out;
  }

  static std::string kind(const YAML::Node& n) {
    return n.IsMap() ? "a map" : n.IsSequence() ? "a list" : n.IsNull() ? "nothing" : fmt::format("'{}'", n.Scalar());
  }

  std::string scalar(const YAML::Node& n, std::string_view key) const {
    if (!n.IsScalar()) fail(n, key, fmt::format("expected a value, got {}", kind(n)));
    return n.Scalar();
  }

  bool boolean(const YAML::Node& n, std::string_view key) const {
    const auto s = scalar(n, key);
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
    fail(n, key, fmt::format("'{}' must be true or false", s));
  }

  long integer(const YAML::Node& n, std::string_view key) const {
    const auto s = scalar(n, key);
    static const std::regex whole(R"(^[+-]?[0-9]{1,9}$)");
    if (!std::regex_match(s, whole)) fail(n, key, fmt::format("'{}' must be a whole number", s));
    return std::stol(s);
  }

  /// A value as `--set KEY=VALUE` takes it: a scalar's text, a list or map in YAML flow style.
  std::string value_text(const YAML::Node& n, std::string_view key) const {
    if (n.IsNull()) fail(n, key, "a value is missing");
    if (n.IsScalar()) return n.Scalar();
    YAML::Emitter e;
    e << YAML::Flow << n;
    return e.c_str();
  }

  /// A scene key named in the study file: declared by the scene, and one that --set can set.
  const config::Key& scene_key(const YAML::Node& key_node, std::string_view context) const {
    const std::string k = key_node.Scalar();
    const config::Key* key = coupling::scene_schema().find(k);
    if (!key || k.find("[]") != std::string::npos)
      fail(key_node, fmt::format("{}.{}", context, k), "not a scene key (flowire help scene lists them)");
    return *key;
  }

  /// A file named in the study file, relative to it: it must be a readable file.
  std::string file(const YAML::Node& n, std::string_view key) const {
    const fs::path rel = scalar(n, key);
    const fs::path p = rel.is_absolute() ? rel : fs::path(file_).parent_path() / rel;
    try {
      check_input_file(p.string(), input_limit::kScene, "a scene (YAML)");
    } catch (const Error& e) {
      fail(n, key, e.what());
    }
    return fs::absolute(p).lexically_normal().string();
  }

  /// `set:` maps (study and case): KEY=VALUE overrides, in the file's order.
  void sets(const YAML::Node& n, const std::string& context, std::vector<std::string>& out,
            std::map<std::string, std::string>& where_of) const {
    if (n.IsNull()) return;
    for (const auto& [k, v] : entries(n, "set", context)) {
      const auto& key = scene_key(k, context);
      out.push_back(key.path + "=" + value_text(v, context + "." + key.path));
      where_of[key.path] = where(k);
    }
  }

  [[nodiscard]] const std::string& name() const { return file_; }

 private:
  std::string file_;
};

std::uint64_t fnv1a(std::uint64_t h, std::string_view bytes) {
  for (const unsigned char c : bytes) h = (h ^ c) * 1099511628211ULL;
  return h;
}

/// A parameter's value as the tables show it: the number in SI (shortest exact form), the text
/// of a choice or a name, a list as [a, b, c].
std::string column_text(const config::Config& cfg, const std::string& key, const std::string& fallback) {
  const auto it = cfg.values().find(key);
  if (it == cfg.values().end()) return fallback;
  const config::Value& v = it->second;
  switch (v.type) {
    case config::Type::Number:
    case config::Type::Integer:
      return fmt::format("{}", v.number);
    case config::Type::Bool:
      return v.boolean ? "true" : "false";
    case config::Type::String:
    case config::Type::Enum:
    case config::Type::StringOrInteger:
      return v.text;
    case config::Type::Vector3:
    case config::Type::NumberList:
      return fmt::format("[{}]", fmt::join(v.list, ", "));
    default:
      return fallback;
  }
}

bool numeric_key(const config::Key& k) {
  return k.type == config::Type::Number || k.type == config::Type::Integer || k.type == config::Type::NumberOrSection;
}

}  // namespace

std::vector<std::string> Quantity::columns() const {
  if (kind == QuantityKind::TipFinal) return {name + "_x", name + "_y", name + "_z"};
  return {name};
}

std::string study_keys_markdown() {
  std::string md = "| key | type | default | description |\n|---|---|---|---|\n";
  for (const auto& k : study_keys())
    md += fmt::format("| `{}` | {} | {} | {} |\n", k.path, k.type, k.default_text, k.doc);
  return md;
}

Study load_study(const std::string& file) {
  Study study;
  study.file = file;
  const std::string text = read_input(file, input_limit::kScene, "a study (YAML)");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw_input_error(fmt::format("{}:{}", file, e.mark.line + 1), fmt::format("YAML syntax error: {}", e.msg));
  }
  const Reader r(file);
  if (!root.IsMap()) throw_input_error(file, "a study must be a map of keys (scene:, parameters:, collect:, ...)");

  // Undefined until given: `if (node)` tells a key that is present. (Each its own node: a
  // yaml-cpp node assigned to takes on the other's value, and copies would share it.)
  YAML::Node scene_node(kAbsent), set_node(kAbsent), params_node(kAbsent), zip_node(kAbsent), cases_node(kAbsent),
      collect_node(kAbsent), pairs_node(kAbsent);
  for (const auto& [k, v] : r.entries(root, "", "")) {
    const std::string key = k.Scalar();
    if (key == "scene") scene_node = v;
    if (key == "set") set_node = v;
    if (key == "parameters") params_node = v;
    if (key == "zip") zip_node = v;
    if (key == "cases") cases_node = v;
    if (key == "collect") collect_node = v;
    if (key == "pairs") pairs_node = v;
    if (key == "keep_runs") {
      const std::string s = r.scalar(v, "keep_runs");
      if (s == "true" || s == "yes")
        study.keep = KeepRuns::All;
      else if (s == "false" || s == "no")
        study.keep = KeepRuns::None;
      else if (s == "failed")
        study.keep = KeepRuns::Failed;
      else
        r.fail(v, "keep_runs", fmt::format("'{}' is not one of: true, false, failed", s));
    }
    if (key == "plot") study.plot = r.boolean(v, "plot");
  }

  // The base scene and the overrides of every run.
  std::string base_scene;
  if (scene_node) base_scene = r.file(scene_node, "scene");
  std::vector<std::string> base_sets;
  std::map<std::string, std::string> set_where;
  if (set_node) r.sets(set_node, "set", base_sets, set_where);

  // Parameters, in the file's order.
  std::map<std::string, size_t> param_index;
  if (params_node) {
    if (params_node.IsNull()) r.fail(params_node, "parameters", "no parameter is given (leave the key out instead)");
    for (const auto& [k, v] : r.entries(params_node, "parameters", "parameters")) {
      const auto& key = r.scene_key(k, "parameters");
      const std::string name = "parameters." + key.path;
      if (set_where.count(key.path)) r.fail(k, name, fmt::format("also fixed by set: ({})", set_where.at(key.path)));
      Parameter p;
      p.key = key.path;
      p.where = r.where(k);
      if (v.IsSequence()) {
        if (v.size() == 0) r.fail(v, name, "an empty list: the product would have no run");
        for (const auto& item : v) {
          p.texts.push_back(r.value_text(item, name));
          p.wheres.push_back(r.where(item));
        }
      } else if (v.IsMap()) {
        YAML::Node from(kAbsent), to(kAbsent), count(kAbsent);
        for (const auto& [rk, rv] : r.entries(v, "parameters.<scene key>", name)) {
          const std::string leaf = rk.Scalar();
          (leaf == "from" ? from : leaf == "to" ? to : count) = rv;
        }
        for (const auto& [n, node] : {std::pair{"from", from}, std::pair{"to", to}, std::pair{"count", count}})
          if (!node) r.fail(v, name, fmt::format("a range needs from, to and count ('{}' is missing)", n));
        if (!numeric_key(key)) r.fail(v, name, "a range needs a number key; give the values of other keys as a list");
        const double a = units::parse_quantity(r.scalar(from, name + ".from"), key.dim, r.where(from) + ": " + name);
        const double b = units::parse_quantity(r.scalar(to, name + ".to"), key.dim, r.where(to) + ": " + name);
        const long n = r.integer(count, name + ".count");
        if (n < 2) r.fail(count, name + ".count", fmt::format("{} must be at least 2", n));
        if (n > 100000) r.fail(count, name + ".count", fmt::format("{} values: at most 100000", n));
        if (a == b) r.fail(v, name, "from and to are equal: give the single value in set: instead");
        for (long i = 0; i < n; ++i) {
          double x = i + 1 == n ? b : a + (b - a) * static_cast<double>(i) / static_cast<double>(n - 1);
          if (key.type == config::Type::Integer) {
            if (std::abs(x - std::round(x)) > 1e-9 * std::max(1.0, std::abs(x)))
              r.fail(v, name,
                     fmt::format("an integer key: the range gives {} (choose from, to and count so that "
                                 "every value is whole)",
                                 x));
            x = std::round(x);
          }
          p.texts.push_back(fmt::format("{}", x));
          p.wheres.push_back(r.where(v));
        }
      } else {
        r.fail(v, name, fmt::format("expected a list of values or a range {{from, to, count}}, got {}", r.kind(v)));
      }
      for (size_t i = 0; i < p.texts.size(); ++i)
        for (size_t j = 0; j < i; ++j)
          if (p.texts[i] == p.texts[j])
            throw_input_error(p.wheres[i], fmt::format("{}: the value '{}' is given twice", name, p.texts[i]));
      param_index[p.key] = study.parameters.size();
      study.parameters.push_back(std::move(p));
    }
  }

  // Zip groups: one axis each, at the place of its first member.
  std::vector<size_t> group_of(study.parameters.size(), SIZE_MAX);
  if (zip_node) {
    if (!zip_node.IsSequence()) r.fail(zip_node, "zip", "expected a list of lists of parameters");
    size_t g = 0;
    for (const auto& group : zip_node) {
      if (!group.IsSequence() || group.size() < 2)
        r.fail(group, "zip", "each group is a list of at least two parameters: [KEY, KEY, ...]");
      size_t length = 0;
      for (const auto& item : group) {
        const std::string k = r.scalar(item, "zip");
        const auto it = param_index.find(k);
        if (it == param_index.end()) r.fail(item, "zip", fmt::format("'{}' is not one of the parameters", k));
        if (group_of[it->second] != SIZE_MAX) r.fail(item, "zip", fmt::format("'{}' is in two groups", k));
        group_of[it->second] = g;
        const size_t len = study.parameters[it->second].texts.size();
        if (length != 0 && len != length)
          r.fail(item, "zip",
                 fmt::format("'{}' has {} values, the group's first parameter {}: zipped lists have equal lengths", k,
                             len, length));
        length = len;
      }
      ++g;
    }
  }
  std::vector<size_t> axis_length;
  {
    std::map<size_t, size_t> axis_of_group;
    for (size_t i = 0; i < study.parameters.size(); ++i) {
      auto& p = study.parameters[i];
      if (group_of[i] != SIZE_MAX && axis_of_group.count(group_of[i])) {
        p.axis = axis_of_group[group_of[i]];
        continue;
      }
      p.axis = axis_length.size();
      axis_length.push_back(p.texts.size());
      if (group_of[i] != SIZE_MAX) axis_of_group[group_of[i]] = p.axis;
    }
  }

  // Cases (the outermost loop); without any, the base scene alone.
  std::vector<std::pair<std::string, YAML::Node>> case_set_nodes;
  if (cases_node) {
    static const std::regex case_name(R"(^[A-Za-z0-9_.-]+$)");
    for (const auto& [k, v] : r.entries(cases_node, "cases", "cases")) {
      const std::string name = k.Scalar();
      const std::string path = "cases." + name;
      if (!std::regex_match(name, case_name))
        r.fail(k, path, "a case's name is letters, digits, '_', '-' and '.' (it names the runs)");
      Case c;
      c.name = name;
      c.where = r.where(k);
      c.scene = base_scene;
      c.sets = base_sets;
      if (!v.IsNull()) {
        std::map<std::string, std::string> case_where;
        for (const auto& [ck, cv] : r.entries(v, "cases.<name>", path)) {
          if (ck.Scalar() == "scene") c.scene = r.file(cv, path + ".scene");
          if (ck.Scalar() == "set") {
            r.sets(cv, path + ".set", c.sets, case_where);
            for (const auto& [key, w] : case_where)
              if (param_index.count(key)) throw_input_error(w, fmt::format("{}.set.{}: also a parameter", path, key));
          }
        }
      }
      if (c.scene.empty()) r.fail(k, path, "no scene: give the study a scene: or the case its own scene:");
      study.cases.push_back(std::move(c));
    }
    if (study.cases.empty()) r.fail(cases_node, "cases", "no case is given (leave the key out instead)");
  } else {
    if (base_scene.empty()) throw_input_error(file, "scene: the base scene is required (scene: FILE.yaml)");
    study.cases.push_back(Case{"", r.where(scene_node), base_scene, base_sets});
  }

  // Quantities.
  static const std::regex column_name(R"(^[A-Za-z_][A-Za-z0-9_]*$)");
  std::set<std::string> columns{"run", "case", "status", "exit_status"};
  std::vector<std::string> summary_top;  // per quantity: the summary section it reads ("" for files)
  if (collect_node) {
    for (const auto& [k, v] : r.entries(collect_node, "collect", "collect")) {
      Quantity q;
      q.name = k.Scalar();
      q.where = r.where(k);
      const std::string path = "collect." + q.name;
      if (!std::regex_match(q.name, column_name))
        r.fail(k, path, "a quantity's name is letters, digits and '_' (it names a column and a PNG)");
      YAML::Node summary(kAbsent), tip(kAbsent), length(kAbsent), clamp(kAbsent);
      for (const auto& [qk, qv] : r.entries(v, "collect.<name>", path)) {
        const std::string leaf = qk.Scalar();
        (leaf == "summary" ? summary : leaf == "tip" ? tip : leaf == "length" ? length : clamp) = qv;
      }
      const int given = (summary ? 1 : 0) + (tip ? 1 : 0) + (clamp ? 1 : 0);
      if (given != 1) r.fail(v, path, "give exactly one of summary:, tip:, clamp_force:");
      std::string top;
      if (summary) {
        q.kind = QuantityKind::Summary;
        q.path = r.scalar(summary, path + ".summary");
        static const std::regex json_path(
            R"(^[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+\])*(\.[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+\])*)*$)");
        if (!std::regex_match(q.path, json_path))
          r.fail(summary, path + ".summary",
                 fmt::format("'{}' is not a path of summary.json (keys joined by '.', list items as [i])", q.path));
        top = q.path.substr(0, q.path.find_first_of(".["));
        const auto& secs = summary_sections();
        if (std::none_of(secs.begin(), secs.end(), [&](const SummarySection& s) { return top == s.name; })) {
          std::string names;
          for (const auto& s : secs) names += (names.empty() ? "" : ", ") + std::string(s.name);
          r.fail(summary, path + ".summary", fmt::format("summary.json has no '{}' (its sections: {})", top, names));
        }
        q.timing = top == "timings";
      } else if (tip) {
        const std::string what = r.scalar(tip, path + ".tip");
        if (what == "final_position") {
          q.kind = QuantityKind::TipFinal;
          if (length) r.fail(length, path + ".length", "only tip: time_to_length takes a length");
        } else if (what == "time_to_length") {
          q.kind = QuantityKind::TipTimeToLength;
          if (!length) r.fail(v, path, "tip: time_to_length needs length: (the inserted length to reach)");
          q.length = units::parse_quantity(r.scalar(length, path + ".length"), units::Dimension::Length,
                                           r.where(length) + ": " + path + ".length");
          if (!(q.length > 0)) r.fail(length, path + ".length", "must be positive");
        } else {
          r.fail(tip, path + ".tip", fmt::format("'{}' is not one of: final_position, time_to_length", what));
        }
      } else {
        const std::string what = r.scalar(clamp, path + ".clamp_force");
        if (what == "max")
          q.kind = QuantityKind::ClampForceMax;
        else if (what == "final")
          q.kind = QuantityKind::ClampForceFinal;
        else
          r.fail(clamp, path + ".clamp_force", fmt::format("'{}' is not one of: max, final", what));
      }
      if (length && q.kind != QuantityKind::TipTimeToLength)
        r.fail(length, path + ".length", "only tip: time_to_length takes a length");
      for (const auto& c : q.columns())
        if (!columns.insert(c).second) r.fail(k, path, fmt::format("the column '{}' is named twice", c));
      summary_top.push_back(top);
      study.quantities.push_back(std::move(q));
    }
  }

  // Pairs (their reference values are found once the runs' values are known).
  std::vector<std::pair<YAML::Node, YAML::Node>> pair_nodes;  // (key, reference)
  if (pairs_node) {
    for (const auto& [k, v] : r.entries(pairs_node, "pairs", "pairs")) {
      Pair p;
      p.name = k.Scalar();
      p.where = r.where(k);
      const std::string path = "pairs." + p.name;
      if (!std::regex_match(p.name, column_name))
        r.fail(k, path, "a pairing's name is letters, digits and '_' (it names rows and a PNG)");
      YAML::Node parameter(kAbsent), reference(kAbsent), spacing(kAbsent);
      for (const auto& [pk, pv] : r.entries(v, "pairs.<name>", path)) {
        const std::string leaf = pk.Scalar();
        (leaf == "parameter" ? parameter : leaf == "reference" ? reference : spacing) = pv;
      }
      if (!parameter || !reference) r.fail(v, path, "a pairing needs parameter: and reference:");
      const std::string key = r.scalar(parameter, path + ".parameter");
      const auto it = param_index.find(key);
      if (it == param_index.end())
        r.fail(parameter, path + ".parameter", fmt::format("'{}' is not one of the parameters", key));
      p.parameter = it->second;
      if (study.parameters[p.parameter].texts.size() < 2)
        r.fail(parameter, path + ".parameter", fmt::format("'{}' has one value: nothing to pair", key));
      if (spacing) {
        p.spacing = units::parse_quantity(r.scalar(spacing, path + ".spacing"), units::Dimension::Length,
                                          r.where(spacing) + ": " + path + ".spacing");
        if (!(p.spacing > 0)) r.fail(spacing, path + ".spacing", "must be positive");
      }
      pair_nodes.emplace_back(k, reference);
      study.pairs.push_back(std::move(p));
    }
  }

  // The runs: cases × the product of the axes, the first axis varying slowest.
  size_t product = 1;
  for (const size_t n : axis_length) {
    if (product > 1000000 / std::max<size_t>(n, 1)) throw_input_error(file, "parameters: more than 10^6 runs");
    product *= n;
  }
  const size_t total = product * study.cases.size();
  if (total > 1000000) throw_input_error(file, "cases × parameters: more than 10^6 runs");
  const int width = std::max(4, static_cast<int>(fmt::format("{}", total - 1).size()));
  std::vector<bool> wire_csv(total), produced(study.quantities.size(), false);
  for (size_t ci = 0; ci < study.cases.size(); ++ci) {
    const Case& c = study.cases[ci];
    try {
      (void)coupling::load_scene(c.scene, c.sets);
    } catch (const Error& e) {
      throw_input_error(c.where,
                        fmt::format("{}: the scene {} refuses it: {}",
                                    c.name.empty() ? std::string("scene") : "cases." + c.name, c.scene, e.what()));
    }
    for (size_t k = 0; k < product; ++k) {
      Run run;
      run.index = study.runs.size();
      run.id = fmt::format("{:0{}}", run.index, width);
      run.case_index = ci;
      run.sets = c.sets;
      std::vector<size_t> at(axis_length.size());
      for (size_t a = axis_length.size(), rest = k; a-- > 0;) at[a] = rest % axis_length[a], rest /= axis_length[a];
      for (const auto& p : study.parameters) {
        run.value.push_back(at[p.axis]);
        run.sets.push_back(p.key + "=" + p.texts[at[p.axis]]);
      }
      config::Config cfg;
      try {
        cfg = coupling::load_scene(c.scene, run.sets);
        if (cfg.has_section("wire")) {
          const auto wire = coupling::scene_wire_spec(cfg);
          if (cfg.has_section("catheter")) (void)coupling::scene_catheter_spec(cfg, wire);
        }
      } catch (const Error& e) {
        // The value to blame: the first parameter the message names, else the first.
        const std::string msg = e.what();
        size_t blame = 0;
        for (size_t i = 0; i < study.parameters.size(); ++i)
          if (msg.find(study.parameters[i].key) != std::string::npos) {
            blame = i;
            break;
          }
        if (study.parameters.empty())
          throw_input_error(c.where, fmt::format("the scene {} refuses it: {}", c.scene, msg));
        std::string values;
        for (const auto& p : study.parameters)
          values += fmt::format("{}{}={}", values.empty() ? "" : ", ", p.key, p.texts[at[p.axis]]);
        const auto& p = study.parameters[blame];
        throw_input_error(p.wheres[at[p.axis]],
                          fmt::format("parameters.{}: the scene refuses run {} ({}{}): {}", p.key, run.id,
                                      c.name.empty() ? "" : "case " + c.name + ", ", values, msg));
      }
      for (const auto& p : study.parameters) run.columns.push_back(column_text(cfg, p.key, p.texts[at[p.axis]]));
      const double dt = cfg.number_or("solve.dt", 0.0);
      const double steps = dt > 0 ? std::max(1.0, cfg.number_or("solve.duration", 0.0) / dt) : 1.0;
      double vertices = 1.0;
      if (cfg.has_section("wire")) {
        const double seg = cfg.has("wire.segment_length") ? cfg.number("wire.segment_length")
                                                          : cfg.number("wire.length") / cfg.number("wire.segments");
        vertices = std::max(1.0, cfg.number("wire.length") / seg);
      }
      run.cost = steps * vertices;
      wire_csv[run.index] = cfg.has_section("wire") && cfg.boolean("output.csv");
      for (size_t qi = 0; qi < study.quantities.size(); ++qi) {
        const auto& q = study.quantities[qi];
        if (q.kind != QuantityKind::Summary) {
          produced[qi] = produced[qi] || wire_csv[run.index];
        } else if (!produced[qi]) {
          for (const auto& s : summary_sections())
            if (summary_top[qi] == s.name && s.written(cfg)) produced[qi] = true;
        }
      }
      study.runs.push_back(std::move(run));
    }
  }
  // Two values that mean the same (1 cm/s and 0.01) would run the same twice.
  for (const auto& p : study.parameters) {
    const size_t pi = static_cast<size_t>(&p - study.parameters.data());
    std::map<std::string, size_t> seen;
    for (const auto& run : study.runs) {
      if (run.case_index != 0) break;
      const auto [it, fresh] = seen.emplace(run.columns[pi], run.value[pi]);
      if (!fresh && it->second != run.value[pi])
        throw_input_error(p.wheres[run.value[pi]],
                          fmt::format("parameters.{}: '{}' is the same value as '{}' ({})", p.key,
                                      p.texts[run.value[pi]], p.texts[it->second], run.columns[pi]));
    }
  }
  for (size_t qi = 0; qi < study.quantities.size(); ++qi) {
    if (produced[qi]) continue;
    const auto& q = study.quantities[qi];
    const std::string why =
        q.kind == QuantityKind::Summary
            ? fmt::format("no run writes summary.json's '{}' (the runs' scenes lack what writes it)", summary_top[qi])
            : "no run writes tip_trace.csv and base_force.csv (they need a wire: and output.csv: true)";
    throw_input_error(q.where, fmt::format("collect.{}: {}", q.name, why));
  }
  for (size_t pi = 0; pi < study.pairs.size(); ++pi) {
    auto& pair = study.pairs[pi];
    const auto& [k, ref] = pair_nodes[pi];
    const Parameter& p = study.parameters[pair.parameter];
    const std::string path = "pairs." + pair.name + ".reference";
    const std::string ref_text = r.scalar(ref, path);
    const config::Key& key = *coupling::scene_schema().find(p.key);
    // The value it names: as written, or (a number key) the same number in SI.
    std::vector<std::string> value_columns(p.texts.size());
    for (const auto& run : study.runs)
      if (run.case_index == 0) value_columns[run.value[pair.parameter]] = run.columns[pair.parameter];
    size_t found = SIZE_MAX;
    for (size_t i = 0; i < p.texts.size() && found == SIZE_MAX; ++i)
      if (p.texts[i] == ref_text || value_columns[i] == ref_text) found = i;
    if (found == SIZE_MAX && numeric_key(key)) {
      double si = 0;
      try {
        si = units::parse_quantity(ref_text, key.dim, r.where(ref));
      } catch (const Error&) {
        si = std::nan("");
      }
      for (size_t i = 0; i < p.texts.size() && found == SIZE_MAX; ++i)
        if (value_columns[i] == fmt::format("{}", si)) found = i;
    }
    if (found == SIZE_MAX)
      r.fail(ref, path,
             fmt::format("'{}' is not one of the values of {} ({})", ref_text, p.key, fmt::join(p.texts, ", ")));
    pair.reference = found;
    if (std::none_of(study.runs.begin(), study.runs.end(), [&](const Run& run) { return wire_csv[run.index]; }))
      r.fail(k, "pairs." + pair.name, "no run writes tip_trace.csv (a wire: and output.csv: true)");
  }

  // The hash that tells this study's results from another's: the study file and its scenes.
  std::uint64_t h = fnv1a(1469598103934665603ULL, text);
  std::set<std::string> scenes;
  for (const auto& c : study.cases) scenes.insert(c.scene);
  for (const auto& s : scenes) {
    h = fnv1a(h, s);
    h = fnv1a(h, read_input(s, input_limit::kScene, "a scene (YAML)"));
  }
  study.hash = fmt::format("{:016x}", h);
  return study;
}

}  // namespace flowire::cli
