#include "support/pdf_check.h"

#include <absl/strings/match.h>
#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

#include "support/subprocess.h"

namespace insdiag::testing {
namespace {

using namespace std::chrono_literals;

// The share of dark pixels of a binary PGM (P5, 8 bits), as pdftoppm -gray writes it.
absl::StatusOr<double> InkFraction(const std::string& pgm) {
  std::istringstream in(pgm);
  std::string magic;
  int width = 0, height = 0, max = 0;
  in >> magic >> width >> height >> max;
  in.get();  // the single whitespace before the pixels
  if (magic != "P5" || width <= 0 || height <= 0 || max != 255) {
    return absl::InternalError(absl::StrCat("not an 8-bit binary PGM: ", magic, " ", width, "x", height, " max ", max));
  }
  const auto start = static_cast<std::size_t>(in.tellg());
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (pgm.size() < start + pixels) return absl::InternalError("the PGM is shorter than its pixels");
  const auto dark = std::count_if(pgm.begin() + static_cast<long>(start), pgm.begin() + static_cast<long>(start + pixels),
                                  [](char c) { return static_cast<unsigned char>(c) < 128; });
  return static_cast<double>(dark) / static_cast<double>(pixels);
}

}  // namespace

absl::Status CheckPdfStructure(const std::string& pdf) {
  if (!absl::StartsWith(pdf, "%PDF-1.")) return absl::InvalidArgumentError("no %PDF-1.x header");
  if (!absl::EndsWith(pdf, "%%EOF\n")) return absl::InvalidArgumentError("does not end with %%EOF");
  const std::size_t startxref = pdf.rfind("startxref\n");
  if (startxref == std::string::npos) return absl::InvalidArgumentError("no startxref");
  std::size_t xref_at = 0;
  const std::size_t number_end = pdf.find('\n', startxref + 10);
  if (!absl::SimpleAtoi(pdf.substr(startxref + 10, number_end - startxref - 10), &xref_at) || xref_at >= pdf.size() ||
      pdf.compare(xref_at, 5, "xref\n") != 0) {
    return absl::InvalidArgumentError("startxref does not point at the xref table");
  }
  std::istringstream table(pdf.substr(xref_at + 5));
  int first = -1, count = 0;
  table >> first >> count;
  table.get();
  if (first != 0 || count < 2) return absl::InvalidArgumentError("the xref section does not start at object 0");
  const std::size_t entries_at = xref_at + 5 + static_cast<std::size_t>(table.tellg());
  for (int i = 0; i < count; ++i) {
    const std::string entry = pdf.substr(entries_at + 20 * static_cast<std::size_t>(i), 20);
    if (entry.size() != 20 || (entry.substr(18) != " \n" && entry.substr(18) != "\r\n")) {
      return absl::InvalidArgumentError(absl::StrCat("xref entry ", i, " is not 20 bytes: '", entry, "'"));
    }
    if (entry[17] != 'n') continue;
    const std::size_t offset = std::stoul(entry.substr(0, 10));
    const std::string expected = absl::StrCat(i, " 0 obj");
    if (pdf.compare(offset, expected.size(), expected) != 0) {
      return absl::InvalidArgumentError(absl::StrCat("xref entry ", i, " points at '", pdf.substr(offset, 12), "'"));
    }
  }
  if (!absl::StrContains(pdf.substr(xref_at), absl::StrCat("/Size ", count, " "))) {
    return absl::InvalidArgumentError(absl::StrCat("the trailer's /Size is not ", count));
  }
  for (std::size_t at = pdf.find("/Length "); at != std::string::npos; at = pdf.find("/Length ", at + 1)) {
    const std::size_t digits_end = pdf.find(' ', at + 8);
    std::size_t declared = 0;
    if (!absl::SimpleAtoi(pdf.substr(at + 8, digits_end - at - 8), &declared)) continue;
    const std::size_t data_at = pdf.find("stream\n", digits_end) + 7;
    if (pdf.compare(data_at + declared, 10, "\nendstream") != 0) {
      return absl::InvalidArgumentError(absl::StrCat("a stream's /Length ", declared, " is not its data's length"));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<RenderedPdf> RenderBack(const std::string& pdf, const std::filesystem::path& dir) {
  const std::string pdftoppm = INSDIAG_PDFTOPPM_PATH;
  const std::string pdftotext = INSDIAG_PDFTOTEXT_PATH;
  if (pdftoppm.empty() || pdftotext.empty()) {
    return absl::UnavailableError("pdftoppm or pdftotext is missing: install poppler-utils (scripts/install-deps.sh)");
  }
  const std::filesystem::path file = dir / "rendered.pdf";
  std::ofstream(file, std::ios::binary) << pdf;
  auto image = RunToCompletion({pdftoppm, "-gray", "-r", "40", file.string(), (dir / "page").string()}, dir, 60s);
  if (!image.ok()) return image.status();
  if (image->exit_status != 0) return absl::InternalError(absl::StrCat("pdftoppm: ", image->stderr_text));
  RenderedPdf out;
  // pdftoppm numbers the pages with as many digits as the last page needs.
  std::vector<std::filesystem::path> pages;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (absl::StartsWith(entry.path().filename().string(), "page-") && entry.path().extension() == ".pgm") {
      pages.push_back(entry.path());
    }
  }
  std::sort(pages.begin(), pages.end());
  for (const auto& page : pages) {
    auto ink = InkFraction(ReadFile(page));
    if (!ink.ok()) return ink.status();
    out.ink_fraction.push_back(*ink);
  }
  auto text = RunToCompletion({pdftotext, "-layout", file.string(), "-"}, dir, 60s);
  if (!text.ok()) return text.status();
  if (text->exit_status != 0) return absl::InternalError(absl::StrCat("pdftotext: ", text->stderr_text));
  out.text = text->stdout_text;
  return out;
}

}  // namespace insdiag::testing
