// Checks of a PDF file for the tests: its structure read back by hand (the
// cross-reference table against the objects it points at), and the file
// rendered back by poppler (pdftoppm, pdftotext from Debian's
// poppler-utils, which scripts/install-deps.sh installs).
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <filesystem>
#include <string>
#include <vector>

namespace insdiag::testing {

// OK when the file starts with a PDF header, ends with %%EOF after a
// startxref that points at the xref table, every in-use entry of that table
// points at "N 0 obj" of its own object number N, the trailer's /Size counts
// the entries, and each stream's /Length is the length of its data.
absl::Status CheckPdfStructure(const std::string& pdf);

struct RenderedPdf {
  // Per page, the share of pixels darker than mid-grey in a grey rendering.
  std::vector<double> ink_fraction;
  std::string text;  // pdftotext's reading of every page
};

// Renders `pdf` (written into `dir`) with pdftoppm and reads it with
// pdftotext. UNAVAILABLE when poppler-utils is not installed; INTERNAL
// when either program fails on the file.
absl::StatusOr<RenderedPdf> RenderBack(const std::string& pdf, const std::filesystem::path& dir);

}  // namespace insdiag::testing
