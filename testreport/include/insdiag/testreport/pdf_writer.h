// A small PDF 1.4 writer (ISO 32000-1 §7): pages of text, lines, polylines
// and filled rectangles, set in two of the standard Type 1 fonts every
// reader has (Helvetica and Helvetica-Bold, §9.6.2.2) with WinAnsiEncoding
// (Annex D.2). No font is embedded and no stream is compressed, so the file
// is plain text apart from the WinAnsi bytes of its strings, which are
// written as octal escapes.
//
// Coordinates are PDF user space: points (1/72 in) from the page's
// lower-left corner, y up. Text is UTF-8; characters WinAnsi lacks are
// spelled out where a reader would understand the spelling (σ → "sigma",
// √ → "sqrt", − → "-") and become "?" otherwise.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <deque>
#include <vector>

namespace insdiag::testreport {

enum class PdfFont { kHelvetica, kHelveticaBold };

struct PdfColor {
  double r = 0.0;  // 0 … 1
  double g = 0.0;
  double b = 0.0;
};

// UTF-8 text as WinAnsi bytes (see above for what WinAnsi lacks).
std::string ToWinAnsi(std::string_view utf8);

// The body of a PDF literal string holding `win_ansi` (§7.3.4.2): "(", ")"
// and "\" escaped with a backslash, bytes outside printable ASCII as \ddd.
std::string EscapePdfString(std::string_view win_ansi);

// The advance width in points of `utf8` set in `font` at `size_pt`, from the
// fonts' published metrics (as the reader will set it; no kerning).
double TextWidthPt(std::string_view utf8, PdfFont font, double size_pt);

// One page's content stream (§8): each call appends operators in a saved
// graphics state, so nothing one call sets leaks into the next.
class PdfPage {
 public:
  void Text(double x_pt, double y_pt, double size_pt, PdfFont font, std::string_view utf8, PdfColor color = {});
  // dash_pt > 0: dashed with dashes and gaps of that length.
  void Line(double x0_pt, double y0_pt, double x1_pt, double y1_pt, double width_pt, PdfColor color,
            double dash_pt = 0.0);
  // A point with a non-finite coordinate breaks the line there.
  void Polyline(std::span<const std::pair<double, double>> points_pt, double width_pt, PdfColor color,
                double dash_pt = 0.0);
  void FillRect(double x_pt, double y_pt, double width_pt, double height_pt, PdfColor color);

  const std::string& content() const { return content_; }

 private:
  std::string content_;
};

// The document information dictionary (§14.3.3).
struct PdfInfo {
  std::string title;
  std::string subject;
  std::string creation_date;  // PDF date, "D:20260126093000Z"; empty: none
};

class PdfDocument {
 public:
  PdfDocument(double page_width_pt, double page_height_pt)
      : page_width_pt_(page_width_pt), page_height_pt_(page_height_pt) {}

  PdfPage& AddPage();
  std::size_t page_count() const { return pages_.size(); }
  PdfPage& page(std::size_t index) { return pages_[index]; }
  double page_width_pt() const { return page_width_pt_; }
  double page_height_pt() const { return page_height_pt_; }

  // The whole file: header, objects, the cross-reference table with each
  // object's byte offset, trailer.
  std::string Serialize(const PdfInfo& info) const;

 private:
  double page_width_pt_;
  double page_height_pt_;
  std::deque<PdfPage> pages_;  // a deque: AddPage keeps earlier pages' references valid
};

}  // namespace insdiag::testreport
