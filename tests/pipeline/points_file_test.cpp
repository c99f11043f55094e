#include "pipeline/input/points_file.h"

#include <gtest/gtest.h>

#include "pipeline/base/input_error.h"
#include "support/refusal.h"

namespace glint {
namespace {

std::string refusal(const std::string& text) {
  return test::refusalOf([&] { parsePoints(text, "P.csv"); });
}

TEST(PointsFile, ReadsRowsInOrderWithTolerantFormatting) {
  // A byte-order mark, CRLF line ends, spaces and a blank line are all common from spreadsheets.
  const auto p = parsePoints("\xEF\xBB\xBFx, y ,z\r\n1,2,3\r\n\r\n -4.5 ,6e-1, 7 \r\n", "P.csv");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_EQ(p[0], Vec3(1, 2, 3));
  EXPECT_EQ(p[1], Vec3(-4.5, 0.6, 7));
}

TEST(PointsFile, RefusesMalformedInputWithTheLineNumber) {
  EXPECT_EQ(refusal("x,y\n1,2\n"), "P.csv:1: the header must be x,y,z (found \"x,y\")");
  EXPECT_EQ(refusal("a,b,c\n1,2,3\n"), "P.csv:1: the header must be x,y,z (found \"a,b,c\")");
  EXPECT_EQ(refusal("x,y,z\n1,2,3\n1,2\n"), "P.csv:3: expected 3 columns (x,y,z), found 2");
  EXPECT_EQ(refusal("x,y,z\n1,2,3,4\n"), "P.csv:2: expected 3 columns (x,y,z), found 4");
  EXPECT_EQ(refusal("x,y,z\n1,abc,3\n"), "P.csv:2: column 2 (y): \"abc\" is not a number");
  EXPECT_EQ(refusal("x,y,z\n1,2,3m\n"), "P.csv:2: column 3 (z): \"3m\" is not a number");
  EXPECT_EQ(refusal("x,y,z\n1,,3\n"), "P.csv:2: column 2 (y): \"\" is not a number");
  EXPECT_EQ(refusal("x,y,z\nnan,2,3\n"), "P.csv:2: column 1 (x): \"nan\" is not finite");
  EXPECT_EQ(refusal("x,y,z\n1,inf,3\n"), "P.csv:2: column 2 (y): \"inf\" is not finite");
  EXPECT_EQ(refusal("x,y,z\n1,2,1e999\n"), "P.csv:2: column 3 (z): \"1e999\" is out of range");
  EXPECT_EQ(refusal("x,y,z\n1,-2e7,3\n"),
            "P.csv:2: column 2 (y): -2e7 m is beyond ±1e7 m, the coordinates glint's arithmetic "
            "carries");
  // Control bytes of a garbage file are escaped: they must not ring or move the terminal.
  EXPECT_EQ(refusal("\x1b[2J\a,y,z\n"),
            "P.csv:1: the header must be x,y,z (found \"\\x1b[2J\\x07,y,z\")");
  EXPECT_EQ(refusal("x,y,z\n1,\x7f,3\n"), "P.csv:2: column 2 (y): \"\\x7f\" is not a number");
  EXPECT_EQ(refusal("x,y,z\n1,2," + std::string(100, '9') + "x\n"),
            "P.csv:2: column 3 (z): \"" + std::string(64, '9') + "…\" is not a number")
      << "a long field is quoted to 64 bytes and an ellipsis";
  EXPECT_EQ(refusal(""), "P.csv: empty file (expected a header x,y,z)");
  EXPECT_EQ(refusal("x,y,z\n\n"), "P.csv: no observer points after the header");
}

}  // namespace
}  // namespace glint
