#pragma once
// The study file of `flowire study` (docs/study.md): its declared keys, and the study it
// describes expanded into runs, each run's scene loaded and checked before anything runs.
#include <cstddef>
#include <string>
#include <vector>

namespace flowire::cli {

/// What a quantity is read from.
enum class QuantityKind {
  Summary,          ///< a summary.json value by its path
  TipFinal,         ///< the last tip position of tip_trace.csv (three columns)
  TipTimeToLength,  ///< the first time the inserted length reaches `length` (tip_trace.csv)
  ClampForceMax,    ///< the largest |F| of base_force.csv
  ClampForceFinal,  ///< the last |F| of base_force.csv
};

struct Quantity {
  std::string name;
  QuantityKind kind = QuantityKind::Summary;
  std::string path;     ///< Summary: "wire.inserted_length", "wire.tip[2]"
  double length = 0.0;  ///< TipTimeToLength: the inserted length to reach (m)
  bool timing = false;  ///< a `timings.` path: written to timings.csv, not to study.csv
  std::string where;    ///< "study.yaml:12"
  /// The table's columns: the name, or NAME_x, NAME_y, NAME_z for a position.
  [[nodiscard]] std::vector<std::string> columns() const;
};

struct Parameter {
  std::string key;                  ///< the scene key
  std::string where;                ///< its place in the study file
  std::vector<std::string> texts;   ///< each value as `--set KEY=VALUE` takes it
  std::vector<std::string> wheres;  ///< where each value is written
  size_t axis = 0;                  ///< the product's axis (a zip group shares one)
};

struct Case {
  std::string name;  ///< empty: the study has no cases (the base scene alone)
  std::string where;
  std::string scene;              ///< absolute path
  std::vector<std::string> sets;  ///< KEY=VALUE, the study's `set` first
};

struct Pair {
  std::string name, where;
  size_t parameter = 0;  ///< index into Study::parameters
  size_t reference = 0;  ///< index of the reference value
  double spacing = 5e-3;
};

struct Run {
  size_t index = 0;
  std::string id;  ///< zero-padded index: the folder runs/<id>
  size_t case_index = 0;
  std::vector<size_t> value;         ///< per parameter: the index of its value
  std::vector<std::string> sets;     ///< every override: the case's, then the parameters'
  std::vector<std::string> columns;  ///< per parameter: its value as the tables show it (SI)
  double cost = 1.0;                 ///< steps × wire vertices: the longest are handed out first
};

enum class KeepRuns { All, None, Failed };

struct Study {
  std::string file;  ///< as given
  std::string hash;  ///< of the study file and every scene it names (hex)
  std::vector<Parameter> parameters;
  std::vector<Case> cases;  ///< at least one
  std::vector<Quantity> quantities;
  std::vector<Pair> pairs;
  KeepRuns keep = KeepRuns::All;
  bool plot = true;
  std::vector<Run> runs;
};

/// @brief Read, check and expand a study file. Every run's scene is loaded with its values.
/// @throws flowire::Error (input) naming the study file, the line and the key.
Study load_study(const std::string& file);

/// @brief The study file's keys as a Markdown table (`flowire help study`, docs/study.md).
std::string study_keys_markdown();

}  // namespace flowire::cli
