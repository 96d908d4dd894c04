#pragma once
/// @file schedule.hpp
/// @brief Driving the wire as a hand or a robot does: a table of base speeds over time.
///
/// `insertion.schedule: FILE.csv` holds the columns `time,speed,rotation_speed` (SI: s, m/s,
/// rad/s; any order, a header naming them first). From each row's time on, the base is
/// pushed (speed > 0), pulled back (< 0) or held (0) and turned at the row's rotation speed,
/// until the next row's time; before the first row it is held. Each step is driven at the
/// schedule's mean over the step, so the inserted length and the base angle at the end of a
/// step are the schedule's integrals up to that time, whatever the rows' times and dt.
#include <string>
#include <vector>

namespace flowire::coupling {

class DriveSchedule {
 public:
  struct Row {
    double time = 0.0;            ///< [s], from which the row holds
    double speed = 0.0;           ///< insertion speed [m/s]
    double rotation_speed = 0.0;  ///< base rotation speed [rad/s], right-handed about the insertion direction
  };

  /// @brief Read a schedule. @throws flowire::Error (input) naming the file and line: missing
  /// file, no header, a missing, unknown or repeated column, a cell that is not a finite
  /// number, a negative time, times not strictly increasing, no row.
  static DriveSchedule read_csv(const std::string& path);

  explicit DriveSchedule(std::vector<Row> rows);

  /// @brief Mean insertion and rotation speeds over [t0, t1] (t1 > t0).
  void mean_over(double t0, double t1, double& speed, double& rotation_speed) const;
  /// @brief ∫₀ᵗ speed, ∫₀ᵗ rotation_speed.
  void integral_to(double t, double& length, double& angle) const;

  [[nodiscard]] const std::vector<Row>& rows() const { return rows_; }

 private:
  std::vector<Row> rows_;
};

}  // namespace flowire::coupling
