#include "flowire/common/config.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "flowire/common/error.hpp"
#include "flowire/common/input.hpp"

namespace flowire::config {

// ---------------------------------------------------------------- Schema

Schema& Schema::add(Key key) {
  if (index_.count(key.path)) throw_usage_error(fmt::format("schema: key '{}' declared twice", key.path));
  index_.emplace(key.path, keys_.size());
  keys_.push_back(std::move(key));
  return *this;
}

Schema& Schema::add(std::string path, Type type, std::string default_text, units::Dimension dim, std::string doc,
                    std::vector<std::string> choices) {
  return add(Key{std::move(path), type, std::move(default_text), dim, std::move(doc), std::move(choices), {}});
}

// ---------------------------------------------------------------- ranges

bool is_numeric(Type type) {
  return type == Type::Number || type == Type::Integer || type == Type::Vector3 || type == Type::NumberList ||
         type == Type::NumberOrSection;
}

bool Range::bounded() const { return std::isfinite(lower) || std::isfinite(upper); }

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  if (lower_open ? !(v > lower) : !(v >= lower)) return false;
  return upper_open ? v < upper : v <= upper;
}

std::string Range::text() const {
  const bool lo = std::isfinite(lower), hi = std::isfinite(upper);
  if (lo && hi) return fmt::format("{}{}, {}{}", lower_open ? '(' : '[', lower, upper, upper_open ? ')' : ']');
  if (lo) return fmt::format("{} {}", lower_open ? ">" : ">=", lower);
  if (hi) return fmt::format("{} {}", upper_open ? "<" : "<=", upper);
  return {};
}

std::string Range::requirement() const {
  const bool lo = std::isfinite(lower), hi = std::isfinite(upper);
  if (lo && hi) return fmt::format("must be in {}", text());
  if (lo && lower == 0.0) return lower_open ? "must be positive (> 0)" : "must not be negative (>= 0)";
  if (lo || hi) return fmt::format("must be {}", text());
  return "must be a finite number";
}

void check_range(const Key& key, double value, std::string_view where, std::string_view path) {
  if (key.range.contains(value)) return;
  const std::string unit = key.dim == units::Dimension::None ? "" : " " + std::string(units::si_unit(key.dim));
  throw_input_error(fmt::format("{}: {} = {}{}", where, path, value, unit),
                    std::isfinite(value) ? key.range.requirement() : "must be a finite number");
}

namespace {

Key& last_numeric(std::vector<Key>& keys, std::string_view what) {
  if (keys.empty()) throw_usage_error(fmt::format("schema: {}() before any key", what));
  Key& k = keys.back();
  if (!is_numeric(k.type)) throw_usage_error(fmt::format("schema: {}() on '{}', which is not a number", what, k.path));
  return k;
}

void check_bounds(const Key& k) {
  const Range& r = k.range;
  const bool empty = r.lower > r.upper || (r.lower == r.upper && (r.lower_open || r.upper_open)) ||
                     std::isnan(r.lower) || std::isnan(r.upper);
  if (empty) throw_usage_error(fmt::format("schema: the range {} of '{}' holds no value", r.text(), k.path));
}

}  // namespace

Schema& Schema::positive() { return above(0.0); }
Schema& Schema::non_negative() { return at_least(0.0); }
Schema& Schema::fraction() { return at_least(0.0).at_most(1.0); }

Schema& Schema::at_least(double v) {
  Key& k = last_numeric(keys_, "at_least");
  k.range.lower = v;
  k.range.lower_open = false;
  check_bounds(k);
  return *this;
}

Schema& Schema::above(double v) {
  Key& k = last_numeric(keys_, "above");
  k.range.lower = v;
  k.range.lower_open = true;
  check_bounds(k);
  return *this;
}

Schema& Schema::at_most(double v) {
  Key& k = last_numeric(keys_, "at_most");
  k.range.upper = v;
  k.range.upper_open = false;
  check_bounds(k);
  return *this;
}

Schema& Schema::below(double v) {
  Key& k = last_numeric(keys_, "below");
  k.range.upper = v;
  k.range.upper_open = true;
  check_bounds(k);
  return *this;
}

const Key* Schema::find(std::string_view path) const {
  auto it = index_.find(path);
  return it == index_.end() ? nullptr : &keys_[it->second];
}

const Key* Schema::find_concrete(std::string_view path, std::string* declared) const {
  std::string decl;
  size_t start = 0;
  while (start <= path.size()) {
    const size_t dot = path.find('.', start);
    const std::string_view part =
        path.substr(start, dot == std::string_view::npos ? std::string_view::npos : dot - start);
    const std::string prefix = decl.empty() ? std::string() : decl + ".";
    if (find(prefix + std::string(part))) {
      decl = prefix + std::string(part);
    } else if (find(prefix + "*")) {
      decl = prefix + "*";
    } else {
      return nullptr;
    }
    if (dot == std::string_view::npos) break;
    start = dot + 1;
  }
  if (declared) *declared = decl;
  return find(decl);
}

namespace {

std::string_view parent_of(std::string_view path) {
  const auto dot = path.rfind('.');
  return dot == std::string_view::npos ? std::string_view{} : path.substr(0, dot);
}

std::string_view leaf_of(std::string_view path) {
  const auto dot = path.rfind('.');
  return dot == std::string_view::npos ? path : path.substr(dot + 1);
}

std::string_view type_name(Type t) {
  switch (t) {
    case Type::Number:
      return "number";
    case Type::Integer:
      return "integer";
    case Type::Bool:
      return "bool";
    case Type::String:
      return "string";
    case Type::Enum:
      return "enum";
    case Type::Vector3:
      return "[x, y, z]";
    case Type::NumberList:
      return "list of numbers";
    case Type::Section:
      return "section";
    case Type::List:
      return "list of sections";
    case Type::NumberOrSection:
      return "number or section";
    case Type::StringOrInteger:
      return "name or index";
  }
  return "?";
}

size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

}  // namespace

std::vector<const Key*> Schema::children(std::string_view path) const {
  std::vector<const Key*> out;
  for (const auto& k : keys_)
    if (parent_of(k.path) == path) out.push_back(&k);
  return out;
}

std::string Schema::markdown() const {
  std::string out = "| key | type | default | unit | range | description |\n|---|---|---|---|---|---|\n";
  for (const auto& k : keys_) {
    std::string type(type_name(k.type));
    if (k.type == Type::Enum) {
      type.clear();
      for (const auto& c : k.choices) type += (type.empty() ? "" : " \\| ") + c;
    }
    const auto unit = k.dim == units::Dimension::None ? std::string_view{} : units::si_unit(k.dim);
    const std::string range = k.range.bounded() ? "`" + k.range.text() + "`" : "";
    out += fmt::format("| `{}` | {} | {} | {} | {} | {} |\n", k.path, type,
                       k.default_text.empty() ? "" : "`" + k.default_text + "`", unit, range, k.doc);
  }
  return out;
}

// ---------------------------------------------------------------- Config accessors

const Value& Config::get(std::string_view path) const {
  auto it = values_.find(path);
  if (it == values_.end()) throw_usage_error(fmt::format("scene key '{}' is not set", path));
  return it->second;
}

bool Config::has(std::string_view path) const { return values_.find(path) != values_.end(); }

bool Config::given(std::string_view path) const {
  const auto it = values_.find(path);
  return it != values_.end() && it->second.where != "default";
}

bool Config::has_section(std::string_view path) const {
  if (has(path)) return true;
  const std::string prefix = std::string(path) + ".";
  auto it = values_.lower_bound(prefix);
  return it != values_.end() && it->first.compare(0, prefix.size(), prefix) == 0;
}

double Config::number(std::string_view path) const { return get(path).number; }
double Config::number_or(std::string_view path, double fallback) const {
  return has(path) ? get(path).number : fallback;
}
int Config::integer(std::string_view path) const { return static_cast<int>(get(path).number); }
bool Config::boolean(std::string_view path) const { return get(path).boolean; }
const std::string& Config::string(std::string_view path) const { return get(path).text; }
std::string Config::string_or(std::string_view path, std::string fallback) const {
  return has(path) ? get(path).text : fallback;
}
Eigen::Vector3d Config::vector3(std::string_view path) const {
  const auto& l = get(path).list;
  return {l.at(0), l.at(1), l.at(2)};
}
const std::vector<double>& Config::list(std::string_view path) const { return get(path).list; }
int Config::count(std::string_view path) const { return has(path) ? static_cast<int>(get(path).number) : 0; }
std::string Config::where(std::string_view path) const {
  auto it = values_.find(path);
  const std::string src = it == values_.end() ? file_ : it->second.where;
  return fmt::format("{}: {}", src, path);
}
std::string Config::resolve_path(std::string_view relative) const {
  namespace fs = std::filesystem;
  fs::path p(relative);
  if (p.is_absolute() || file_.empty()) return p.string();
  return (fs::path(file_).parent_path() / p).lexically_normal().string();
}

// ---------------------------------------------------------------- loading

namespace {

class Loader {
 public:
  Loader(const Schema& schema, std::string name, Config& out, std::set<std::string> overridden)
      : schema_(schema), name_(std::move(name)), out_(out), overridden_(std::move(overridden)) {}

  std::string where(const YAML::Node& node) const {
    if (in_defaults_) return "default";  // a declared default: its own text, in no file
    if (node.Mark().is_null() || node.Mark().line < 0) return "--set";
    return fmt::format("{}:{}", name_, node.Mark().line + 1);
  }

  void unknown_key(const YAML::Node& key_node, const std::string& decl_path) const {
    const Key* best = nullptr;
    size_t best_d = 4;
    for (const auto& k : schema_.keys()) {
      if (parent_of(k.path) != parent_of(decl_path)) continue;
      const size_t d = edit_distance(leaf_of(k.path), leaf_of(decl_path));
      if (d < best_d) best_d = d, best = &k;
    }
    std::string allowed;
    for (const auto* k : schema_.children(parent_of(decl_path)))
      allowed += (allowed.empty() ? "" : ", ") + std::string(leaf_of(k->path));
    const std::string hint =
        best ? fmt::format(" (did you mean '{}'?)", leaf_of(best->path)) : fmt::format(" (allowed here: {})", allowed);
    throw_input_error(where(key_node), fmt::format("unknown key '{}'{}", decl_path, hint));
  }

  void map(const YAML::Node& node, const std::string& decl, const std::string& concrete) {
    if (!node.IsMap()) {
      const std::string at = overridden_.count(concrete) ? std::string("--set") : where(node);
      if (decl.size() > 2 && decl.ends_with(".*")) {
        // A section that takes named entries (a branch's own values): a misspelt key lands here.
        const std::string parent = decl.substr(0, decl.size() - 2);
        std::string allowed;
        for (const auto* k : schema_.children(parent))
          if (!k->path.ends_with(".*")) allowed += (allowed.empty() ? "" : ", ") + std::string(leaf_of(k->path));
        throw_input_error(at, fmt::format("'{}' is not a key of {} (allowed: {}), and as a named entry it must be a "
                                          "map of keys",
                                          concrete, parent, allowed));
      }
      throw_input_error(at, fmt::format("'{}' must be a map of keys", concrete.empty() ? "scene" : concrete));
    }
    for (const auto& kv : node) {
      if (!kv.first.IsScalar())  // "? [a, b]: 1": YAML allows lists and maps as keys; a scene does not
        throw_input_error(where(kv.first), "a key must be a name, not a list or a map");
      const auto key = kv.first.as<std::string>();
      const std::string dpath = decl.empty() ? key : decl + "." + key;
      const std::string cpath = concrete.empty() ? key : concrete + "." + key;
      const Key* k = schema_.find(dpath);
      std::string declared = dpath;
      if (!k && schema_.find(decl + ".*")) {  // a named entry of a section that takes names
        declared = decl + ".*";
        k = schema_.find(declared);
      }
      if (!k) unknown_key(kv.first, dpath);
      value(kv.second, *k, declared, cpath);
    }
  }

  void value(const YAML::Node& node, const Key& k, const std::string& dpath, const std::string& cpath) {
    Value v;
    v.type = k.type;
    v.where = overridden_.count(cpath) ? std::string("--set") : where(node);
    const std::string w = fmt::format("{}: {}", v.where, cpath);
    auto scalar = [&]() -> std::string {
      if (!node.IsScalar())
        throw_input_error(w, fmt::format("expected a {}, got a {}", type_name(k.type),
                                         node.IsMap()        ? "map"
                                         : node.IsSequence() ? "list"
                                                             : "null"));
      return node.Scalar();
    };
    switch (k.type) {
      case Type::Section:
        if (!node.IsNull()) map(node, dpath, cpath);
        break;
      case Type::NumberOrSection:
        if (node.IsMap()) {
          v.type = Type::Section;
          map(node, dpath, cpath);
        } else {
          v.type = Type::Number;
          v.number = units::parse_quantity(scalar(), k.dim, w);
          check_range(k, v.number, v.where, cpath);
        }
        break;
      case Type::List: {
        if (!node.IsSequence()) throw_input_error(w, "expected a list");
        int i = 0;
        for (const auto& item : node) map(item, dpath + "[]", fmt::format("{}[{}]", cpath, i++));
        v.number = i;
        break;
      }
      case Type::Number:
        v.number = units::parse_quantity(scalar(), k.dim, w);
        check_range(k, v.number, v.where, cpath);
        break;
      case Type::Integer: {
        v.number = units::parse_quantity(scalar(), units::Dimension::None, w);
        if (v.number != std::floor(v.number) || std::abs(v.number) > 2e9)
          throw_input_error(w, fmt::format("'{}' must be a whole number", node.Scalar()));
        check_range(k, v.number, v.where, cpath);
        break;
      }
      case Type::Bool: {
        const auto s = scalar();
        if (s == "true" || s == "yes" || s == "on")
          v.boolean = true;
        else if (s == "false" || s == "no" || s == "off")
          v.boolean = false;
        else
          throw_input_error(w, fmt::format("'{}' must be true or false", s));
        break;
      }
      case Type::String:
      case Type::StringOrInteger:
        v.text = scalar();
        break;
      case Type::Enum: {
        v.text = scalar();
        if (std::find(k.choices.begin(), k.choices.end(), v.text) == k.choices.end()) {
          std::string c;
          for (const auto& x : k.choices) c += (c.empty() ? "" : ", ") + x;
          throw_input_error(w, fmt::format("'{}' is not one of: {}", v.text, c));
        }
        break;
      }
      case Type::Vector3:
      case Type::NumberList: {
        if (!node.IsSequence()) throw_input_error(w, fmt::format("expected a {}", type_name(k.type)));
        for (const auto& item : node) {
          if (!item.IsScalar()) throw_input_error(w, "list items must be numbers");
          v.list.push_back(units::parse_quantity(item.Scalar(), k.dim, w));
        }
        if (k.type == Type::Vector3 && v.list.size() != 3)
          throw_input_error(w, fmt::format("expected 3 numbers [x, y, z], got {}", v.list.size()));
        for (size_t i = 0; i < v.list.size(); ++i) check_range(k, v.list[i], v.where, fmt::format("{}[{}]", cpath, i));
        break;
      }
    }
    out_.set(cpath, std::move(v));
  }

  void defaults() {
    // Keys are declared parents-first, so a defaulted section makes its children's defaults apply.
    for (const auto& k : schema_.keys()) {
      if (k.default_text.empty()) continue;
      const std::string parent(parent_of(k.path));
      std::vector<std::string> parents;
      if (parent.empty()) {
        parents.emplace_back();
      } else if (parent.size() > 2 && parent.compare(parent.size() - 2, 2, "[]") == 0) {
        const std::string list = parent.substr(0, parent.size() - 2);
        const int n = out_.count(list);
        for (int i = 0; i < n; ++i) parents.push_back(fmt::format("{}[{}]", list, i));
      } else {
        std::string concrete = parent;  // a section below list items is not defaulted
        // Children are defaulted under a section given (or defaulted) as a map, not under a
        // number-or-section key given as a number.
        if (out_.has(concrete) && out_.values().at(concrete).type == Type::Section) parents.push_back(concrete);
      }
      for (const auto& p : parents) {
        const std::string cpath = p.empty() ? std::string(leaf_of(k.path)) : p + "." + std::string(leaf_of(k.path));
        if (out_.has(cpath) || out_.has_section(cpath)) continue;
        YAML::Node node = YAML::Load(k.default_text);
        in_defaults_ = true;
        value(node, k, k.path, cpath);
        in_defaults_ = false;
        out_.set(cpath, [&] {
          Value v = out_.values().at(cpath);
          v.where = "default";
          return v;
        }());
      }
    }
  }

 private:
  const Schema& schema_;
  std::string name_;
  Config& out_;
  std::set<std::string> overridden_;
  bool in_defaults_ = false;
};

std::string apply_override(YAML::Node& root, const std::string& text, const Schema& schema) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) throw_input_error("--set", fmt::format("'{}' must be KEY=VALUE", text));
  const std::string path = text.substr(0, eq);
  const std::string val = text.substr(eq + 1);
  if (!schema.find_concrete(path)) throw_input_error("--set", fmt::format("unknown key '{}'", path));
  YAML::Node value;
  try {
    value = YAML::Load(val);
  } catch (const YAML::Exception& e) {
    throw_input_error("--set", fmt::format("{}: cannot parse '{}': {}", path, val, e.msg));
  }
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
  // Walk down, creating maps as needed. yaml-cpp nodes are handles: reassigning a
  // local Node would rebind it, so keep them in a vector.
  std::vector<YAML::Node> chain{root};
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node next = chain.back()[parts[i]];
    if (next.IsScalar()) {  // e.g. pressure: 13000 overridden by pressure.waveform=sine
      chain.back()[parts[i]] = YAML::Node(YAML::NodeType::Map);
      next = chain.back()[parts[i]];
    }
    chain.push_back(next);
  }
  YAML::Node clean = YAML::Clone(value);
  chain.back()[parts.back()] = clean;
  return path;
}

}  // namespace

Config load_config_text(const std::string& text, const std::string& name, const Schema& schema,
                        const std::vector<std::string>& overrides) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw_input_error(fmt::format("{}:{}", name, e.mark.line + 1), fmt::format("YAML syntax error: {}", e.msg));
  }
  if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  if (!root.IsMap()) throw_input_error(name, "a scene must be a map of sections (vessels:, flow:, wire:, ...)");
  std::set<std::string> overridden;
  for (const auto& o : overrides) overridden.insert(apply_override(root, o, schema));
  Config cfg;
  cfg.set_file(name);
  Loader loader(schema, name, cfg, std::move(overridden));
  try {
    loader.map(root, "", "");
  } catch (const YAML::Exception& e) {  // a conversion the checks above did not foresee: still one line, exit 2
    throw_input_error(fmt::format("{}:{}", name, e.mark.line + 1), e.msg);
  }
  loader.defaults();
  return cfg;
}

Config declared_defaults(const Schema& schema, std::string_view section) {
  const Key* key = schema.find(section);
  if (!key || key->type != Type::Section)
    throw_usage_error(fmt::format("declared_defaults: '{}' is not a declared section", section));
  YAML::Node root(YAML::NodeType::Map);
  std::vector<YAML::Node> chain{root};  // handles, as in apply_override
  std::stringstream ss{std::string(section)};
  for (std::string part; std::getline(ss, part, '.');) {
    chain.back()[part] = YAML::Node(YAML::NodeType::Map);
    chain.push_back(chain.back()[part]);
  }
  Config cfg;
  Loader loader(schema, "default", cfg, {});
  loader.map(root, "", "");
  loader.defaults();
  for (const auto& [path, v] : cfg.values()) {
    Value d = v;
    d.where = "default";
    cfg.set(path, std::move(d));
  }
  return cfg;
}

Config load_config(const std::string& file, const Schema& schema, const std::vector<std::string>& overrides) {
  return load_config_text(read_input(file, input_limit::kScene, "a scene (YAML)"), file, schema, overrides);
}

}  // namespace flowire::config
