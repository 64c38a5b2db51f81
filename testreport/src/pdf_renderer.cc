// The document laid out on A4 pages: blocks flow top to bottom and a block
// that would cross the bottom margin starts a new page (a table continues on
// the next page under its repeated header), so no text is ever cut.
#include <absl/strings/str_cat.h>
#include <absl/strings/str_split.h>

#include <algorithm>
#include <numeric>

#include "insdiag/testreport/pdf_writer.h"
#include "insdiag/testreport/test_report.h"
#include "plot_drawing.h"

namespace insdiag::testreport {
namespace {

// A4 in points (ISO 216: 210 × 297 mm).
constexpr double kPageWidth = 595.276;
constexpr double kPageHeight = 841.89;
constexpr double kMargin = 48.0;
constexpr double kTopMargin = 54.0;
constexpr double kBottomMargin = 54.0;
constexpr double kContentWidth = kPageWidth - 2 * kMargin;
constexpr double kBodySize = 9.0;
constexpr double kBodyLeading = 12.0;
constexpr double kTableSize = 7.5;
constexpr double kTableLeading = 9.5;
constexpr double kCellPad = 3.0;
constexpr double kPlotHeight = 175.0;

constexpr PdfColor kInk{0.1, 0.1, 0.1};
constexpr PdfColor kMuted{0.38, 0.38, 0.38};
constexpr PdfColor kRule{0.75, 0.75, 0.75};
constexpr PdfColor kHeaderFill{0.92, 0.92, 0.92};

// A tone's pale background and its strong mark (the callout's bar and headline).
struct ToneColors {
  PdfColor tint;
  PdfColor strong;
};

ToneColors ColorsOf(Tone tone) {
  switch (tone) {
    case Tone::kGood: return {{0.89, 0.95, 0.9}, {0.16, 0.5, 0.23}};
    case Tone::kWarning: return {{1.0, 0.95, 0.83}, {0.69, 0.49, 0.0}};
    case Tone::kBad: return {{0.98, 0.88, 0.87}, {0.7, 0.15, 0.12}};
    case Tone::kNeutral: break;
  }
  return {{0.95, 0.95, 0.95}, kMuted};
}

PdfFont FontOf(bool bold) { return bold ? PdfFont::kHelveticaBold : PdfFont::kHelvetica; }

// `text` broken into lines no wider than `width`: at spaces, and inside a
// word only when the word alone is wider (a hash, a resource name).
std::vector<std::string> Wrap(const std::string& text, double size, bool bold, double width) {
  std::vector<std::string> lines;
  std::string line;
  const auto fits = [&](const std::string& s) { return TextWidthPt(s, FontOf(bold), size) <= width; };
  for (absl::string_view word_view : absl::StrSplit(text, ' ', absl::SkipEmpty())) {
    std::string word(word_view);
    const std::string joined = line.empty() ? word : absl::StrCat(line, " ", word);
    if (fits(joined)) {
      line = joined;
      continue;
    }
    if (!line.empty()) lines.push_back(line);
    line.clear();
    while (!fits(word)) {
      // The longest prefix that fits, whole UTF-8 characters only.
      std::size_t cut = word.size();
      while (cut > 1 && (!fits(word.substr(0, cut)) || (static_cast<unsigned char>(word[cut]) & 0xC0) == 0x80)) --cut;
      lines.push_back(word.substr(0, cut));
      word = word.substr(cut);
    }
    line = word;
  }
  if (!line.empty() || lines.empty()) lines.push_back(line);
  return lines;
}

// Draws a plot at a place on a page: the canvas's y runs down from `top_`.
class PdfCanvas final : public Canvas {
 public:
  PdfCanvas(PdfPage& page, double left, double top) : page_(page), left_(left), top_(top) {}
  void Polyline(const std::vector<std::pair<double, double>>& points, double width, Rgb color, bool dashed) override {
    std::vector<std::pair<double, double>> placed;
    placed.reserve(points.size());
    for (const auto& [x, y] : points) placed.push_back({left_ + x, kPageHeight - (top_ + y)});
    page_.Polyline(placed, width, {color.r, color.g, color.b}, dashed ? 2.5 : 0.0);
  }
  void Rect(double x, double y, double width, double height, Rgb fill) override {
    page_.FillRect(left_ + x, kPageHeight - (top_ + y + height), width, height, {fill.r, fill.g, fill.b});
  }
  void Text(double x, double y, double size, Anchor anchor, bool bold, const std::string& text, Rgb color) override {
    const double w = TextWidthPt(text, FontOf(bold), size);
    const double shift = anchor == Anchor::kStart ? 0.0 : anchor == Anchor::kMiddle ? w / 2 : w;
    page_.Text(left_ + x - shift, kPageHeight - (top_ + y), size, FontOf(bold), text, {color.r, color.g, color.b});
  }

 private:
  PdfPage& page_;
  double left_;
  double top_;
};

class Layout {
 public:
  explicit Layout(PdfDocument& pdf) : pdf_(pdf) { NewPage(); }

  void Title(const Document& d);
  // `keep_with` points of what follows stay on the heading's page.
  void Heading(const std::string& title, double keep_with);
  void Add(const Paragraph& p) { TextLines(p.text, kBodySize, false, kInk, kMargin, kContentWidth), y_ += 4; }
  void Add(const Callout& c);
  void Add(const Fields& f);
  void Add(const Table& t);
  void Add(const Plot& p);
  void Footers(const std::string& footer);

 private:
  void NewPage() {
    page_ = &pdf_.AddPage();
    y_ = kTopMargin;
  }
  // Starts a new page unless `height` more points fit on this one.
  void Ensure(double height) {
    if (y_ + height > kPageHeight - kBottomMargin && y_ > kTopMargin) NewPage();
  }
  // Text at the cursor: `y_` is the top of the line.
  void Line(double x, double size, bool bold, const std::string& text, PdfColor color) {
    page_->Text(x, kPageHeight - (y_ + size), size, FontOf(bold), text, color);
  }
  void TextLines(const std::string& text, double size, bool bold, PdfColor color, double x, double width) {
    for (const auto& line : Wrap(text, size, bold, width)) {
      Ensure(kBodyLeading);
      Line(x, size, bold, line, color);
      y_ += size * kBodyLeading / kBodySize;
    }
  }
  std::vector<double> ColumnWidths(const Table& t) const;
  void TableRow(const std::vector<std::string>& cells, const std::vector<double>& widths, bool header, Tone tone);

  PdfDocument& pdf_;
  PdfPage* page_ = nullptr;
  double y_ = 0;  // the cursor, points down from the page's top edge
};

void Layout::Title(const Document& d) {
  Line(kMargin, 18, true, d.title, kInk);
  y_ += 26;
  TextLines(d.subtitle, 10, false, kMuted, kMargin, kContentWidth);
  TextLines(absl::StrCat("Generated ", d.generated_at), 9, false, kMuted, kMargin, kContentWidth);
  y_ += 4;
}

void Layout::Heading(const std::string& title, double keep_with) {
  Ensure(34 + keep_with);  // a heading stays with the start of its section
  y_ += 10;
  Line(kMargin, 13, true, title, kInk);
  y_ += 17;
  page_->Line(kMargin, kPageHeight - y_, kMargin + kContentWidth, kPageHeight - y_, 0.6, kRule);
  y_ += 7;
}

void Layout::Add(const Callout& c) {
  const auto detail = Wrap(c.detail, 9.5, false, kContentWidth - 24);
  const double height = 14 + 20 + static_cast<double>(detail.size()) * 12.5 + 6;
  Ensure(height);
  page_->FillRect(kMargin, kPageHeight - (y_ + height), kContentWidth, height, ColorsOf(c.tone).tint);
  page_->FillRect(kMargin, kPageHeight - (y_ + height), 5, height, ColorsOf(c.tone).strong);
  y_ += 8;
  Line(kMargin + 14, 16, true, c.headline, ColorsOf(c.tone).strong);
  y_ += 24;
  for (const auto& line : detail) {
    Line(kMargin + 14, 9.5, false, line, kInk);
    y_ += 12.5;
  }
  y_ += 10;
}

void Layout::Add(const Fields& f) {
  double label_width = 0;
  for (const auto& [label, value] : f.items) label_width = std::max(label_width, TextWidthPt(label, FontOf(true), kBodySize));
  label_width = std::min(label_width + 10, kContentWidth / 3);
  for (const auto& [label, value] : f.items) {
    const auto labels = Wrap(label, kBodySize, true, label_width - 6);
    const auto values = Wrap(value, kBodySize, false, kContentWidth - label_width);
    Ensure(kBodyLeading * static_cast<double>(std::max(labels.size(), values.size())));
    const double top = y_;
    for (const auto& l : labels) Line(kMargin, kBodySize, true, l, kInk), y_ += kBodyLeading;
    const double after_labels = y_;
    y_ = top;
    for (const auto& v : values) Line(kMargin + label_width, kBodySize, false, v, kInk), y_ += kBodyLeading;
    y_ = std::max(y_, after_labels);
  }
  y_ += 6;
}

// Each column's natural width where the table fits; where it does not, the
// narrow columns keep theirs and the wide ones share the rest equally (and wrap).
std::vector<double> Layout::ColumnWidths(const Table& t) const {
  const std::size_t n = t.header.size();
  std::vector<double> natural(n, 0.0);
  for (std::size_t c = 0; c < n; ++c) {
    natural[c] = TextWidthPt(t.header[c], FontOf(true), kTableSize);
    for (const auto& row : t.rows) {
      if (c < row.size()) natural[c] = std::max(natural[c], TextWidthPt(row[c], FontOf(false), kTableSize));
    }
    natural[c] += 2 * kCellPad + 1;
  }
  const double total = std::accumulate(natural.begin(), natural.end(), 0.0);
  std::vector<double> widths(n);
  if (total <= kContentWidth) {
    for (std::size_t c = 0; c < n; ++c) widths[c] = natural[c] * kContentWidth / total;
    return widths;
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return natural[a] < natural[b]; });
  double remaining = kContentWidth;
  for (std::size_t i = 0; i < n; ++i) {
    const double share = remaining / static_cast<double>(n - i);
    widths[order[i]] = std::min(natural[order[i]], share);
    remaining -= widths[order[i]];
  }
  return widths;
}

void Layout::TableRow(const std::vector<std::string>& cells, const std::vector<double>& widths, bool header,
                      Tone tone) {
  std::vector<std::vector<std::string>> wrapped;
  std::size_t lines = 1;
  for (std::size_t c = 0; c < widths.size(); ++c) {
    wrapped.push_back(Wrap(c < cells.size() ? cells[c] : "", kTableSize, header, widths[c] - 2 * kCellPad));
    lines = std::max(lines, wrapped.back().size());
  }
  const double height = static_cast<double>(lines) * kTableLeading + 2 * kCellPad;
  if (header || tone != Tone::kNeutral) {
    page_->FillRect(kMargin, kPageHeight - (y_ + height), kContentWidth, height, header ? kHeaderFill : ColorsOf(tone).tint);
  }
  double x = kMargin;
  for (std::size_t c = 0; c < widths.size(); ++c) {
    double line_top = y_ + kCellPad;
    for (const auto& text : wrapped[c]) {
      page_->Text(x + kCellPad, kPageHeight - (line_top + kTableSize), kTableSize, FontOf(header), text, kInk);
      line_top += kTableLeading;
    }
    x += widths[c];
  }
  y_ += height;
  page_->Line(kMargin, kPageHeight - y_, kMargin + kContentWidth, kPageHeight - y_, 0.4, kRule);
}

void Layout::Add(const Table& t) {
  const std::vector<double> widths = ColumnWidths(t);
  Ensure(3 * kTableLeading + 4 * kCellPad);
  TableRow(t.header, widths, true, Tone::kNeutral);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    std::size_t lines = 1;
    for (std::size_t c = 0; c < widths.size() && c < t.rows[i].size(); ++c) {
      lines = std::max(lines, Wrap(t.rows[i][c], kTableSize, false, widths[c] - 2 * kCellPad).size());
    }
    const double height = static_cast<double>(lines) * kTableLeading + 2 * kCellPad;
    if (y_ + height > kPageHeight - kBottomMargin) {
      NewPage();
      TableRow(t.header, widths, true, Tone::kNeutral);
    }
    TableRow(t.rows[i], widths, false, i < t.row_tones.size() ? t.row_tones[i] : Tone::kNeutral);
  }
  y_ += 4;
  if (!t.caption.empty()) TextLines(t.caption, 8, false, kMuted, kMargin, kContentWidth);
  y_ += 6;
}

void Layout::Add(const Plot& p) {
  Ensure(kPlotHeight + 8);
  PdfCanvas canvas(*page_, kMargin, y_);
  DrawPlot(p, kContentWidth, kPlotHeight, canvas);
  y_ += kPlotHeight + 10;
}

void Layout::Footers(const std::string& footer) {
  const std::size_t n = pdf_.page_count();
  for (std::size_t i = 0; i < n; ++i) {
    PdfPage& page = pdf_.page(i);
    const std::string number = absl::StrCat("page ", i + 1, " of ", n);
    const double baseline = kBottomMargin / 2;
    const double number_width = TextWidthPt(number, PdfFont::kHelvetica, 7.5);
    const auto text = Wrap(footer, 7.5, false, kContentWidth - number_width - 12).front();
    page.Line(kMargin, baseline + 10, kMargin + kContentWidth, baseline + 10, 0.4, kRule);
    page.Text(kMargin, baseline, 7.5, PdfFont::kHelvetica, text, kMuted);
    page.Text(kMargin + kContentWidth - number_width, baseline, 7.5, PdfFont::kHelvetica, number, kMuted);
  }
}

// "2026-01-26T09:30:00Z" → "D:20260126093000Z" (PDF's date string, §7.9.4).
std::string PdfDate(const std::string& rfc3339) {
  std::string digits;
  for (const char c : rfc3339.substr(0, 19)) {
    if (c >= '0' && c <= '9') digits += c;
  }
  return digits.size() == 14 ? absl::StrCat("D:", digits, "Z") : "";
}

}  // namespace

std::string RenderPdf(const Document& document) {
  PdfDocument pdf(kPageWidth, kPageHeight);
  Layout layout(pdf);
  layout.Title(document);
  for (const Section& section : document.sections) {
    // A plot is kept whole with its heading; other blocks by a few lines.
    const bool plot_first = !section.blocks.empty() && std::holds_alternative<Plot>(section.blocks.front());
    layout.Heading(section.title, plot_first ? kPlotHeight + 10 : 50);
    for (const Block& block : section.blocks) {
      std::visit([&layout](const auto& b) { layout.Add(b); }, block);
    }
  }
  layout.Footers(document.footer);
  return pdf.Serialize({document.title, document.subtitle, PdfDate(document.generated_at)});
}

}  // namespace insdiag::testreport
