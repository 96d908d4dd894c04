#include "flowire/coupling/trace_compare.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "flowire_test.hpp"

using namespace flowire::coupling;

namespace {
std::vector<TracePoint> line_trace(double offset, double step, double len) {
  std::vector<TracePoint> t;
  for (double L = 0; L <= len + 1e-12; L += step) t.push_back({L, L, Eigen::Vector3d(L, offset, 0)});
  return t;
}
}  // namespace

TEST(TraceCompare, IdenticalTracesHaveZeroDistance) {
  const auto a = line_trace(0, 1e-3, 0.2);
  const auto r = compare_traces(a, a);
  EXPECT_EQ(r.samples, 41);
  EXPECT_EQ(r.rms_total, 0.0);
}

TEST(TraceCompare, ConstantOffsetGivesItsValueAndThePublishedNormalisation) {
  // Different sampling of inserted length on each side: resampling must not matter.
  const auto a = line_trace(0, 0.7e-3, 0.2);
  const auto b = line_trace(2e-3, 1.3e-3, 0.2);
  const auto r = compare_traces(a, b, 5e-3, 50e-3);
  ASSERT_EQ(r.rows.size(), 4u);
  EXPECT_NEAR(r.rms_total, 2e-3, 1e-12);
  EXPECT_NEAR(r.rms_published_total, std::sqrt(0.5 * r.samples) * 2e-3, 1e-12);
  for (const auto& row : r.rows) EXPECT_NEAR(row.rms, 2e-3, 1e-12);
  EXPECT_NEAR(r.rows[0].inserted_length, 0.05, 1e-12);
}

TEST(TraceCompare, OnlyTheCommonRangeIsCompared) {
  const auto a = line_trace(0, 1e-3, 0.1);
  const auto b = line_trace(0, 1e-3, 0.3);
  EXPECT_NEAR(compare_traces(a, b).rows.back().inserted_length, 0.1, 1e-12);
}
