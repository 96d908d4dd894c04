#pragma once
/// @file block.hpp
/// @brief The base of every svZeroDSolver block, how a block reads its parameters by name,
/// and the registry that makes a block from its type name in the JSON model.
#include <Eigen/Core>
#include <functional>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "flowire/flow/svzerod/param.hpp"
#include "flowire/flow/svzerod/system.hpp"

namespace flowire::flow::svzerod {

/// @brief A connection between two blocks: its flow and pressure unknowns.
struct Node {
  std::string name;  ///< "upstream:downstream"
  int q = -1;        ///< flow unknown
  int p = -1;        ///< pressure unknown
};

/// @brief The parameters of one block in the JSON model, read by name. Keys not asked for
/// (other than the time list `t` and `_comments`) are refused by finish().
class BlockInput {
 public:
  /// @param values the block's parameter object
  /// @param file model file; @param block block name (both for messages)
  /// @param period the model's period so far (-1: none yet); a table with another period is refused
  BlockInput(const nlohmann::json& values, std::string file, std::string block, double& period);
  /// @brief A required parameter (number or list over `t`).
  Param param(const std::string& key);
  /// @brief An optional parameter, `fallback` when absent.
  Param param(const std::string& key, double fallback);
  /// @brief A required list of numbers (one per outlet, ...).
  std::vector<double> numbers(const std::string& key);
  /// @brief param() and numbers() of a quantity that cannot be negative (a resistance, a
  /// capacitance, an inductance, a stenosis coefficient): a value below 0, in a table too, is
  /// refused by fail() naming the parameter.
  Param nonnegative(const std::string& key);
  Param nonnegative(const std::string& key, double fallback);
  std::vector<double> nonnegative_numbers(const std::string& key);
  /// @brief An optional flag.
  bool flag(const std::string& key, bool fallback);
  /// @brief True when a parameter read so far is a table over time.
  [[nodiscard]] bool any_table() const { return any_table_; }
  [[nodiscard]] const std::string& name() const { return block_; }
  /// @brief Refuse keys that were not asked for.
  void finish() const;
  /// @brief Input error naming the file and the block.
  [[noreturn]] void fail(const std::string& what) const;

 private:
  void require_nonnegative(const std::string& key) const;

  const nlohmann::json& values_;
  std::string file_, block_;
  double& period_;
  std::vector<std::string> asked_;
  bool any_table_ = false;
};

/// @brief One block of the network: a set of equation rows (num_equations()) over the flow
/// and pressure unknowns of its connections and its own internal unknowns.
class Block {
 public:
  explicit Block(std::string name) : name_(std::move(name)) {}
  virtual ~Block() = default;
  Block(const Block&) = delete;
  Block& operator=(const Block&) = delete;

  [[nodiscard]] const std::string& name() const { return name_; }
  /// @brief The type name in the JSON model (BloodVessel, RCR, ...).
  [[nodiscard]] virtual const char* type() const = 0;

  void add_inlet(const Node& n) { inlets_.push_back(n); }
  void add_outlet(const Node& n) { outlets_.push_back(n); }
  [[nodiscard]] const std::vector<Node>& inlets() const { return inlets_; }
  [[nodiscard]] const std::vector<Node>& outlets() const { return outlets_; }
  /// @brief Empty when the connections suit the block, else what is wrong with them.
  [[nodiscard]] virtual std::string check_connections() const = 0;

  /// @brief True when the block makes the pressures of all its connections equal: the model
  /// may then give them one pressure unknown, and the block writes no equation for it.
  [[nodiscard]] virtual bool equal_pressures() const { return false; }
  /// @brief Number of equation rows (once connected).
  [[nodiscard]] virtual int num_equations() const = 0;
  /// @brief Names (prefixes) of the block's own unknowns, e.g. "pressure_c".
  [[nodiscard]] virtual std::vector<std::string> internal_unknowns() const { return {}; }
  /// @brief Place the block's rows from `first_row` and its own unknowns from `first_internal`.
  void place(int first_row, int first_internal) {
    row0_ = first_row;
    internal0_ = first_internal;
  }

  /// @brief Write the linear part (E, F, c) at time t; a.steady() in the steady initial phase.
  virtual void assemble(Assembler& a, double t) const = 0;
  /// @brief Write the nonlinear part and its derivatives at (y, ẏ); only if nonlinear().
  virtual void assemble_nonlinear(Assembler& /*a*/, double /*t*/, const Eigen::VectorXd& /*y*/,
                                  const Eigen::VectorXd& /*yd*/) const {}
  /// @brief True when the linear part depends on time (a parameter is a table).
  [[nodiscard]] virtual bool time_dependent() const { return time_dependent_; }
  [[nodiscard]] virtual bool nonlinear() const { return false; }
  /// @brief Before the pulsatile phase, with the state it starts from.
  virtual void prepare(const Eigen::VectorXd& /*y*/, const Eigen::VectorXd& /*yd*/, bool /*after_steady*/,
                       double /*period*/) {}
  /// @brief Longest time constant of the block at t = 0 (cycles to converge).
  [[nodiscard]] virtual double time_constant() const { return 0.0; }

 protected:
  /// The single connection of a boundary condition.
  [[nodiscard]] const Node& port() const { return inlets_.empty() ? outlets_[0] : inlets_[0]; }
  std::string name_;
  std::vector<Node> inlets_, outlets_;
  int row0_ = -1, internal0_ = -1;
  bool time_dependent_ = false;
};

/// @brief Where a block type appears in the JSON model.
enum class Section { Vessel, BoundaryCondition, Junction };

/// @brief Block types by name: the only place that knows which classes exist.
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Block>(BlockInput&)>;
  /// @brief The registry with every supported block type.
  static const Registry& instance();
  /// @brief Make a block; unknown type (or a type of another section): input error naming
  /// the file, the block and the supported types.
  [[nodiscard]] std::unique_ptr<Block> create(Section section, const std::string& type, BlockInput& in) const;
  /// @brief Supported type names of a section, comma-separated.
  [[nodiscard]] std::string supported(Section section) const;
  [[nodiscard]] bool has(Section section, const std::string& type) const;

 private:
  Registry();
  void add(Section s, std::string type, Factory f);
  struct Entry {
    Section section;
    std::string type;
    Factory make;
  };
  std::vector<Entry> entries_;
};

}  // namespace flowire::flow::svzerod
