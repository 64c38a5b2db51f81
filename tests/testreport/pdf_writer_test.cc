// The PDF writer: a file readers accept (its cross-reference table read back
// by hand, then rendered by poppler), its strings escaped, its text measured
// with the fonts' metrics.
#include "insdiag/testreport/pdf_writer.h"

#include <absl/strings/match.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "support/pdf_check.h"
#include "support/subprocess.h"

namespace insdiag::testreport {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kA4Width = 595.276;
constexpr double kA4Height = 841.89;

PdfDocument TwoPages() {
  PdfDocument pdf(kA4Width, kA4Height);
  PdfPage& first = pdf.AddPage();
  first.Text(72, 770, 14, PdfFont::kHelveticaBold, "Verdict (FAULTY) \\ back");
  first.FillRect(72, 600, 200, 100, {0.3, 0.1, 0.1});
  const std::vector<std::pair<double, double>> zigzag = {{72, 500}, {150, 560}, {230, 480}, {300, 540}};
  first.Polyline(zigzag, 1.5, {0, 0, 0.8});
  PdfPage& second = pdf.AddPage();
  second.Line(72, 400, 520, 400, 2, {}, 3);
  second.Text(72, 380, 11, PdfFont::kHelvetica, "±3σ at 20 °C, γ² = 5.24");
  return pdf;
}

TEST(PdfWriter, CrossReferenceOffsetsPointAtTheirObjects) {
  const std::string file = TwoPages().Serialize({"A title (with parentheses)", "subject", "D:20260126093000Z"});
  EXPECT_TRUE(absl::StartsWith(file, "%PDF-1.4\n"));
  EXPECT_TRUE(testing::CheckPdfStructure(file).ok()) << testing::CheckPdfStructure(file);
  EXPECT_THAT(file, HasSubstr("/Count 2"));
  EXPECT_THAT(file, HasSubstr("/BaseFont /Helvetica /Encoding /WinAnsiEncoding"));
  EXPECT_THAT(file, HasSubstr("/BaseFont /Helvetica-Bold /Encoding /WinAnsiEncoding"));
  EXPECT_THAT(file, HasSubstr("/Title (A title \\(with parentheses\\))"));

  // The check itself fails on a file whose offsets are off by one byte.
  const std::size_t first_object = file.find("1 0 obj");
  ASSERT_NE(first_object, std::string::npos);
  const std::string shifted = file.substr(0, first_object) + " " + file.substr(first_object);
  EXPECT_FALSE(testing::CheckPdfStructure(shifted).ok());
}

TEST(PdfWriter, EscapesParenthesesBackslashAndBytesOutsideAscii) {
  EXPECT_EQ(EscapePdfString("a(b)c\\d"), "a\\(b\\)c\\\\d");
  EXPECT_EQ(EscapePdfString("\xB1\n"), "\\261\\012");
  const std::string content = TwoPages().page(0).content();
  EXPECT_THAT(content, HasSubstr("(Verdict \\(FAULTY\\) \\\\ back) Tj"));
}

TEST(PdfWriter, TextIsWinAnsiWithTheStatisticsGreekSpelledOut) {
  EXPECT_EQ(ToWinAnsi("±3σ at 20 °C, µ"), "\xB1" "3sigma at 20 \xB0" "C, \xB5");
  EXPECT_EQ(ToWinAnsi("γ² ≤ η² − 1 … €"), "gamma\xB2 <= eta\xB2 - 1 \x85 \x80");
  // A character WinAnsi lacks and nothing spells becomes "?"; so does a
  // malformed UTF-8 sequence, without swallowing what follows it.
  EXPECT_EQ(ToWinAnsi("日x"), "?x");
  EXPECT_EQ(ToWinAnsi("a\xFF" "b\xE2\x82"), "a?b??");
}

TEST(PdfWriter, WidthsFollowTheFontsMetrics) {
  // Helvetica: H 722, i 222 per 1000 em; Helvetica-Bold: H 722, i 278.
  EXPECT_DOUBLE_EQ(TextWidthPt("Hi", PdfFont::kHelvetica, 10), 9.44);
  EXPECT_DOUBLE_EQ(TextWidthPt("Hi", PdfFont::kHelveticaBold, 10), 10.0);
  EXPECT_DOUBLE_EQ(TextWidthPt("", PdfFont::kHelvetica, 10), 0.0);
  // "σ" is set as "sigma": its width is that of the spelling.
  EXPECT_DOUBLE_EQ(TextWidthPt("σ", PdfFont::kHelvetica, 10), TextWidthPt("sigma", PdfFont::kHelvetica, 10));
}

TEST(PdfWriter, ANonFiniteCoordinateBreaksThePolylineAndNoNumberIsNan) {
  PdfDocument pdf(kA4Width, kA4Height);
  PdfPage& page = pdf.AddPage();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<double, double>> points = {{0, 0}, {10, 10}, {nan, 5}, {20, 0}, {30, 10}};
  page.Polyline(points, 1, {});
  const std::string& content = page.content();
  EXPECT_THAT(content, HasSubstr("0 0 m\n10 10 l\n20 0 m\n30 10 l\n"));
  EXPECT_THAT(content, Not(HasSubstr("nan")));
  // A line of lone points strokes nothing.
  PdfPage& empty = pdf.AddPage();
  const std::vector<std::pair<double, double>> lone = {{0, 0}, {nan, 1}, {5, 5}};
  empty.Polyline(lone, 1, {});
  EXPECT_EQ(empty.content(), "");
}

TEST(PdfWriter, PopplerRendersEveryPageWithInkAndReadsItsText) {
  const std::filesystem::path dir = testing::MakeTempDir("insdiag-pdf-writer");
  auto rendered = testing::RenderBack(TwoPages().Serialize({"t", "s", ""}), dir);
  if (absl::IsUnavailable(rendered.status())) GTEST_SKIP() << rendered.status().message();
  ASSERT_TRUE(rendered.ok()) << rendered.status();
  ASSERT_EQ(rendered->ink_fraction.size(), 2u);
  EXPECT_GT(rendered->ink_fraction[0], 0.01);  // the filled rectangle alone is 2 % of the page
  EXPECT_GT(rendered->ink_fraction[1], 0.0005);
  EXPECT_THAT(rendered->text, HasSubstr("Verdict (FAULTY) \\ back"));
  EXPECT_THAT(rendered->text, HasSubstr("±3sigma at 20 °C, gamma² = 5.24"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace insdiag::testreport
