#include "slslam/core/check.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace slslam {
namespace {

int built = 0;
int Count() { return ++built; }

TEST(Check, MessagePartsAreEvaluatedOnlyOnFailure) {
  built = 0;
  SLSLAM_CHECK(1 + 1 == 2, "never built ", Count());
  EXPECT_EQ(built, 0);
  try {
    SLSLAM_CHECK(1 + 1 == 3, "width ", 752, " != ", 640, " (call ", Count(), ")");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "width 752 != 640 (call 1)");
  }
  EXPECT_EQ(built, 1);
}

TEST(Check, RequireWithALiteralAndAString) {
  EXPECT_NO_THROW(Require(true, "fine"));
  EXPECT_THROW(Require(false, "bad"), std::invalid_argument);
  EXPECT_THROW(Require(false, std::string("bad")), std::invalid_argument);
}

}  // namespace
}  // namespace slslam
