// Line reading, splitting, parsing and the shared checks of the text readers.
#include "core/io/text_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tests/core/io/io_test_util.h"

namespace navtwin {
namespace io_text_reader_test {

using testing::ExpectInputError;
using testing::WriteTempFile;

TEST(TextReaderTest, LineReaderHandlesLfCrLfAndCrEndsAndCountsBytes) {
  const std::string path = WriteTempFile("ends.txt", "a\r\nbb\rc\n\nd");
  LineReader r(path);
  std::string line;
  struct Expected {
    const char* text;
    LineEnd end;
    std::uint64_t end_offset;
  };
  const Expected expected[] = {{"a", LineEnd::kCrLf, 3},
                               {"bb", LineEnd::kCr, 6},
                               {"c", LineEnd::kLf, 8},
                               {"", LineEnd::kLf, 9},
                               {"d", LineEnd::kNone, 10}};
  long n = 0;
  for (const Expected& e : expected) {
    ASSERT_TRUE(r.Next(&line));
    ++n;
    EXPECT_EQ(line, e.text);
    EXPECT_EQ(r.line_end(), e.end);
    EXPECT_EQ(r.end_offset(), e.end_offset);
    EXPECT_EQ(r.line_number(), n);
  }
  EXPECT_FALSE(r.Next(&line));
  EXPECT_FALSE(r.Next(&line));
}

// The reader takes the file in blocks: a line longer than a block, and a CR LF whose
// two bytes fall into two blocks, come out whole, with their byte offsets.
TEST(TextReaderTest, LinesAcrossBlockBoundariesComeOutWhole) {
  constexpr std::size_t kBlock = LineReader::kBlockBytes;
  const std::string longest(kBlock + 100, 'x');
  const std::string first(kBlock - 2, 'y');  // "y...y\r" ends the first block, "\n" starts the next
  const std::string text = first + "\r\n" + longest + "\nz\r";
  LineReader r(WriteTempFile("blocks.txt", text));
  std::string line;
  ASSERT_TRUE(r.Next(&line));
  EXPECT_EQ(line, first);
  EXPECT_EQ(r.line_end(), LineEnd::kCrLf);
  EXPECT_EQ(r.end_offset(), kBlock);
  ASSERT_TRUE(r.Next(&line));
  EXPECT_EQ(line, longest);
  EXPECT_EQ(r.line_end(), LineEnd::kLf);
  EXPECT_EQ(r.end_offset(), kBlock + longest.size() + 1);
  ASSERT_TRUE(r.Next(&line));
  EXPECT_EQ(line, "z");
  EXPECT_EQ(r.line_end(), LineEnd::kCr);
  EXPECT_EQ(r.end_offset(), text.size());
  EXPECT_EQ(r.line_number(), 3);
  EXPECT_FALSE(r.Next(&line));
}

TEST(TextReaderTest, MissingFileIsAnInputErrorNamingIt) {
  ExpectInputError([] { LineReader r("/nonexistent/navtwin.txt"); },
                   {"/nonexistent/navtwin.txt", "cannot open"});
}

TEST(TextReaderTest, SplitCsvKeepsEmptyFieldsAndTrims) {
  std::vector<std::string_view> f;
  SplitCsv(" a, b,,c ,", &f);
  ASSERT_EQ(f.size(), 5u);
  EXPECT_EQ(f[0], "a");
  EXPECT_EQ(f[1], "b");
  EXPECT_EQ(f[2], "");
  EXPECT_EQ(f[3], "c");
  EXPECT_EQ(f[4], "");
}

TEST(TextReaderTest, SplitLooseTreatsBlankAndCommaRunsAsOneSeparator) {
  std::vector<std::string_view> f;
  SplitLoose("  1 2,3\t, 4 \r", &f);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[3], "4");
}

TEST(TextReaderTest, StripUnitRemovesParenthesisedUnits) {
  EXPECT_EQ(StripUnit(" compass_heading(degrees)"), "compass_heading");
  EXPECT_EQ(StripUnit("North"), "North");
}

TEST(TextReaderTest, ParseDoubleAcceptsNumbersAndRejectsTheRest) {
  EXPECT_EQ(ParseDouble("+1.5", "f", 3, "x"), 1.5);
  EXPECT_EQ(ParseDouble("-2e-3", "f", 3, "x"), -2e-3);
  ExpectInputError([] { ParseDouble("1.5x", "f.txt", 3, "x"); },
                   {"f.txt:line 3", "field 'x'", "not a number: '1.5x'"});
  ExpectInputError([] { ParseDouble("", "f.txt", 3, "x"); }, {"not a number"});
  ExpectInputError([] { ParseDouble("NaN", "f.txt", 4, "y"); },
                   {"line 4", "field 'y'", "not a finite number"});
  ExpectInputError([] { ParseDouble("-Infinity", "f.txt", 4, "y"); }, {"not a finite number"});
  ExpectInputError([] { ParseDouble("1e999", "f.txt", 4, "y"); }, {"not a finite number"});
}

TEST(TextReaderTest, IntegerAndWholeNumberParsing) {
  EXPECT_EQ(ParseInteger("4294967295", "f", 1, "t"), 4294967295LL);
  ExpectInputError([] { ParseInteger("12.5", "f", 1, "t"); }, {"not an integer"});
  EXPECT_EQ(ParseWholeNumber("25.0000000", "f", 1, "ns"), 25);
  ExpectInputError([] { ParseWholeNumber("2.5", "f", 1, "Q"); }, {"field 'Q'", "whole number"});
}

TEST(TextReaderTest, RequirePositiveRejectsZeroAndNegative) {
  RequirePositive(1e-9, "f", 1, "sigma");
  ExpectInputError([] { RequirePositive(0.0, "f", 7, "sigma_n"); },
                   {"line 7", "field 'sigma_n'", "must be > 0"});
  ExpectInputError([] { RequirePositive(-1.0, "f", 7, "sigma_n"); }, {"must be > 0"});
  // Subnormal: > 0, but 1/sigma^2 overflows and the value has lost its precision.
  ExpectInputError([] { RequirePositive(1e-320, "f", 7, "sigma_n"); }, {"f", "line 7", "sigma_n", "subnormal"});
  RequirePositive(std::numeric_limits<double>::min(), "f", 1, "sigma");
}

TEST(TextReaderTest, IncreasingTimeRejectsRepeatsAndStepsBack) {
  IncreasingTime time;
  time.Check(1.0, "f", 1, "t");
  time.Check(2.0, "f", 2, "t");
  ExpectInputError([&] { time.Check(2.0, "f", 3, "t"); },
                   {"line 3", "field 't'", "does not increase", "at line 2"});
  IncreasingTime back;
  back.Check(5.0, "f", 1, "t");
  ExpectInputError([&] { back.Check(4.0, "f", 2, "t"); }, {"line 2"});
}

TEST(TextReaderTest, HeaderColumnsFindByNameIgnoringCase) {
  const std::vector<std::string_view> names = {"t_s", " Acc_X ", "gyro_x_dps"};
  const HeaderColumns h(names, "f.csv", 1);
  EXPECT_EQ(h.Find("acc_x"), 1);
  EXPECT_EQ(h.Find("acc_y"), -1);
  EXPECT_EQ(h.Require("GYRO_X_DPS"), 2);
  ExpectInputError([&] { h.Require("dv_z_mps"); }, {"f.csv:line 1", "missing column 'dv_z_mps'"});
}

TEST(TextReaderTest, RequireFieldCountNamesBothCounts) {
  ExpectInputError([] { RequireFieldCount(6, 7, "f", 9); },
                   {"line 9", "expected 7 columns, found 6"});
}

}  // namespace io_text_reader_test
}  // namespace navtwin
