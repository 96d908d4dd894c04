// Exceptions (common/src/error.cpp): each helper throws flowire::Error of its kind, and an
// input error reads "<where>: <what>" as the command line prints it.
#include "flowire/common/error.hpp"

#include <gtest/gtest.h>

#include <string>

#include "flowire_test.hpp"

namespace flowire {
namespace {

template <class F>
Error caught(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no flowire::Error thrown";
  return Error(ErrorKind::Usage, "");
}

TEST(Error, AnInputErrorNamesTheFileAndPlace) {
  const Error e = caught([] { throw_input_error("aorta.vtp: point 17", "radius -1 is not positive"); });
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_EQ(std::string(e.what()), "aorta.vtp: point 17: radius -1 is not positive");
  const Error bare = caught([] { throw_input_error("", "no file to name"); });
  EXPECT_EQ(bare.kind(), ErrorKind::Input);
  EXPECT_EQ(std::string(bare.what()), "no file to name");
}

TEST(Error, UsageAndNumericalErrorsKeepTheirMessageAndKind) {
  const Error u = caught([] { throw_usage_error("depth must be in 0..24"); });
  EXPECT_EQ(u.kind(), ErrorKind::Usage);
  EXPECT_EQ(std::string(u.what()), "depth must be in 0..24");
  const Error n = caught([] { throw_numerical_error("singular matrix"); });
  EXPECT_EQ(n.kind(), ErrorKind::Numerical);
  EXPECT_EQ(std::string(n.what()), "singular matrix");
}

TEST(Error, IsARuntimeErrorForCallersThatCatchTheStandardType) {
  EXPECT_THROW(throw_input_error("f", "w"), std::runtime_error);
  EXPECT_THROW(throw_usage_error("w"), std::runtime_error);
  EXPECT_THROW(throw_numerical_error("w"), std::runtime_error);
}

}  // namespace
}  // namespace flowire
