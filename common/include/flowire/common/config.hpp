#pragma once
/// @file config.hpp
/// @brief Declared, validated configuration trees (the scene file).
///
/// Every key is declared once in a `Schema` (type, default, unit, range, doc). `load_config`
/// reads YAML, applies `--set` overrides, rejects unknown keys naming file and line,
/// converts "<number> <unit>" strings to SI, refuses numbers outside their key's range, and
/// fills defaults for every section that is present. A section that is absent stays absent:
/// nothing of it is run.
#include <Eigen/Core>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "flowire/common/units.hpp"

namespace flowire::config {

enum class Type {
  Number,           ///< real, optionally "<number> <unit>"
  Integer,          ///< whole number
  Bool,             ///< true / false
  String,           ///< free text (file names, node names)
  Enum,             ///< one of `choices`
  Vector3,          ///< [x, y, z], each optionally with a unit
  NumberList,       ///< [a, b, ...]
  Section,          ///< a map whose children are declared keys
  List,             ///< a list of maps; item keys are declared as "<path>[].<key>"
  NumberOrSection,  ///< either a number (with unit) or a map with declared children
  StringOrInteger,  ///< a name or an index (e.g. a node)
};

/// @brief The values a number accepts (in SI): a lower and an upper bound, each closed (the
/// bound itself is allowed) or open; a side without a bound is infinite. Whatever the bounds,
/// a number must be finite.
struct Range {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool lower_open = false;  ///< true: > lower; false: >= lower
  bool upper_open = false;  ///< true: < upper; false: <= upper

  /// @brief True if either side has a bound.
  [[nodiscard]] bool bounded() const;
  /// @brief True if @p v is finite and within the bounds.
  [[nodiscard]] bool contains(double v) const;
  /// @brief The bounds as the reference page shows them: "> 0", ">= 0", "[0, 1]", "(0, 1.5)",
  /// "<= 24"; empty without bounds.
  [[nodiscard]] std::string text() const;
  /// @brief What a value outside says: "must be positive (> 0)", "must not be negative (>= 0)",
  /// "must be in [0, 1]", "must be a finite number".
  [[nodiscard]] std::string requirement() const;
};

/// @brief True for the types whose values are numbers (Number, Integer, Vector3, NumberList,
/// NumberOrSection): those a Range applies to (a vector's or list's every component).
[[nodiscard]] bool is_numeric(Type type);

struct Key {
  std::string path;  ///< dotted path, e.g. "flow.inlet.pressure"; list items "loads[].type"
  Type type = Type::Number;
  std::string default_text;  ///< YAML text of the default; empty: no default (absent unless given)
  units::Dimension dim = units::Dimension::None;
  std::string doc;
  std::vector<std::string> choices;  ///< for Enum
  Range range;                       ///< numeric types: the values accepted (default: any finite number)
};

/// @brief Refuse a value of @p key outside its range: an input error at @p where (a file and
/// line, "--set", ...) naming @p path (the concrete key, "loads[0].s"), the value with its SI
/// unit and the range: "scene.yaml:12: wire.length = -0.5 m: must be positive (> 0)".
void check_range(const Key& key, double value, std::string_view where, std::string_view path);

class Schema {
 public:
  Schema& add(Key key);
  /// @brief Declare a key: add(Key{path, type, default_text, dim, doc, choices}).
  Schema& add(std::string path, Type type, std::string default_text, units::Dimension dim, std::string doc,
              std::vector<std::string> choices = {});

  /// @name The range of the key declared last, chained after add():
  /// `s.add("wire.length", ...).positive();`, `s.add("fem.frames", ...).at_least(0).at_most(1e5);`.
  /// Each sets one side (a later call on the same side replaces it).
  /// @throws flowire::Error (usage) if that key is not numeric or the bounds leave no value.
  ///@{
  Schema& positive();          ///< > 0
  Schema& non_negative();      ///< >= 0
  Schema& fraction();          ///< [0, 1]
  Schema& at_least(double v);  ///< >= v
  Schema& above(double v);     ///< > v
  Schema& at_most(double v);   ///< <= v
  Schema& below(double v);     ///< < v
  ///@}
  [[nodiscard]] const Key* find(std::string_view path) const;
  /// @brief The key a concrete path is declared by: the path itself, or with names in place
  /// of a declared wildcard `<section>.*` ("flow.outlets.left_iliac.rcr.Rp" is declared as
  /// "flow.outlets.*.rcr.Rp"). The declared path in @p declared. Null if none.
  [[nodiscard]] const Key* find_concrete(std::string_view path, std::string* declared = nullptr) const;
  [[nodiscard]] const std::vector<Key>& keys() const { return keys_; }
  /// @brief Children declared directly under `path` ("" for the top level).
  [[nodiscard]] std::vector<const Key*> children(std::string_view path) const;
  /// @brief The reference page: one table row per key (path, type, default, unit, range, doc).
  [[nodiscard]] std::string markdown() const;

 private:
  std::vector<Key> keys_;
  std::map<std::string, size_t, std::less<>> index_;
};

/// @brief One resolved value, in SI, with the place it came from.
struct Value {
  Type type = Type::Number;
  double number = 0.0;
  bool boolean = false;
  std::string text;
  std::vector<double> list;
  std::string where;  ///< "scene.yaml:12" or "--set" or "default"
};

/// @brief A validated scene: flat map from concrete path ("loads[0].type") to value.
class Config {
 public:
  [[nodiscard]] bool has(std::string_view path) const;
  /// @brief True if the key was given (in the scene or by --set), not only filled in from its
  /// declared default.
  [[nodiscard]] bool given(std::string_view path) const;
  /// @brief True if a section (or any key below it) was given or defaulted.
  [[nodiscard]] bool has_section(std::string_view path) const;
  [[nodiscard]] double number(std::string_view path) const;
  [[nodiscard]] double number_or(std::string_view path, double fallback) const;
  [[nodiscard]] int integer(std::string_view path) const;
  [[nodiscard]] bool boolean(std::string_view path) const;
  [[nodiscard]] const std::string& string(std::string_view path) const;
  [[nodiscard]] std::string string_or(std::string_view path, std::string fallback) const;
  [[nodiscard]] Eigen::Vector3d vector3(std::string_view path) const;
  [[nodiscard]] const std::vector<double>& list(std::string_view path) const;
  /// @brief Number of items of a List key.
  [[nodiscard]] int count(std::string_view path) const;
  /// @brief Where a value came from, for error messages ("scene.yaml:12: flow.solver").
  [[nodiscard]] std::string where(std::string_view path) const;
  [[nodiscard]] const std::map<std::string, Value, std::less<>>& values() const { return values_; }
  /// @brief The file the config was read from (empty for strings).
  [[nodiscard]] const std::string& file() const { return file_; }
  /// @brief Directory of that file, for resolving relative file names.
  [[nodiscard]] std::string resolve_path(std::string_view relative) const;
  /// @brief Set a value programmatically (used by loaders and tests).
  void set(std::string path, Value v) { values_[std::move(path)] = std::move(v); }
  void set_file(std::string f) { file_ = std::move(f); }

 private:
  const Value& get(std::string_view path) const;
  std::map<std::string, Value, std::less<>> values_;
  std::string file_;
};

/// @brief Read a YAML scene file, apply `--set KEY=VALUE` overrides, validate against `schema`.
/// @throws flowire::Error (input) naming file, line and key.
Config load_config(const std::string& file, const Schema& schema, const std::vector<std::string>& overrides = {});
/// @brief The values of a scene that gives @p section empty: the defaults its keys declare
/// (their place "default"). For a section whose keys act even where a scene leaves it out
/// (a wire in vessels touches the walls without a contact: section), so that the code reading
/// it does not state those defaults a second time.
/// @throws flowire::Error (usage) if @p section is not a declared section.
Config declared_defaults(const Schema& schema, std::string_view section);
/// @brief Same, from YAML text (`name` is used in messages in place of a file name).
Config load_config_text(const std::string& text, const std::string& name, const Schema& schema,
                        const std::vector<std::string>& overrides = {});

}  // namespace flowire::config
