// The document as one self-contained HTML5 file: the style inline, the
// plots as inline SVG, no script and no external resource, so that the file
// opens the same on any machine, offline, years later.
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <string_view>

#include "insdiag/testreport/test_report.h"
#include "plot_drawing.h"

namespace insdiag::testreport {
namespace {

// The plots' drawing size in CSS pixels; the SVG scales to the page's width.
constexpr double kPlotWidth = 720.0;
constexpr double kPlotHeight = 190.0;

constexpr char kStyle[] = R"(
body { font-family: Helvetica, Arial, sans-serif; font-size: 10.5pt; color: #1a1a1a; max-width: 62rem; margin: 2rem auto; padding: 0 1rem; }
h1 { font-size: 1.6rem; margin: 0; }
h2 { font-size: 1.15rem; border-bottom: 1px solid #999; padding-bottom: .2rem; margin-top: 1.8rem; }
.subtitle, .generated { color: #555; margin: .2rem 0; }
.callout { border-left: .5rem solid #777; padding: .6rem 1rem; margin: .8rem 0; background: #f2f2f2; }
.callout .headline { font-size: 1.5rem; font-weight: bold; }
.tone-good { background: #e3f3e6; border-color: #2a7f3a; }
.tone-warning { background: #fff3d4; border-color: #b07d00; }
.tone-bad { background: #fbe0de; border-color: #b3261e; }
dl { display: grid; grid-template-columns: max-content auto; gap: .15rem 1rem; }
dt { font-weight: bold; }
dd { margin: 0; overflow-wrap: anywhere; }
table { border-collapse: collapse; width: 100%; margin: .6rem 0 .2rem; font-size: 9.5pt; }
th, td { border: 1px solid #ccc; padding: .2rem .4rem; text-align: left; vertical-align: top; }
th { background: #eee; }
tr.tone-bad td { background: #fbe0de; }
tr.tone-warning td { background: #fff3d4; }
tr.tone-good td { background: #e3f3e6; }
.caption { color: #555; font-size: 9pt; margin: .1rem 0 .8rem; }
figure { margin: 1rem 0; }
figure svg { width: 100%; height: auto; }
footer { color: #555; font-size: 9pt; border-top: 1px solid #999; margin-top: 2rem; padding-top: .4rem; }
@media print { body { margin: 0; max-width: none; } figure, table, .callout { break-inside: avoid; } }
)";

std::string Escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

const char* ToneClass(Tone tone) {
  switch (tone) {
    case Tone::kGood: return "tone-good";
    case Tone::kWarning: return "tone-warning";
    case Tone::kBad: return "tone-bad";
    case Tone::kNeutral: break;
  }
  return "tone-neutral";
}

std::string Css(const Rgb& c) {
  return absl::StrFormat("rgb(%d,%d,%d)", static_cast<int>(c.r * 255 + 0.5), static_cast<int>(c.g * 255 + 0.5),
                         static_cast<int>(c.b * 255 + 0.5));
}

class SvgCanvas final : public Canvas {
 public:
  void Polyline(const std::vector<std::pair<double, double>>& points, double width, Rgb color, bool dashed) override {
    absl::StrAppend(&svg_, "<polyline fill=\"none\" stroke=\"", Css(color), "\" stroke-width=\"", width, "\"",
                    dashed ? " stroke-dasharray=\"3 2\"" : "", " points=\"");
    for (const auto& [x, y] : points) absl::StrAppendFormat(&svg_, "%.1f,%.1f ", x, y);
    svg_ += "\"/>\n";
  }
  void Rect(double x, double y, double width, double height, Rgb fill) override {
    absl::StrAppendFormat(&svg_, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n", x, y,
                          width, height, Css(fill));
  }
  void Text(double x, double y, double size, Anchor anchor, bool bold, const std::string& text, Rgb color) override {
    const char* anchors[] = {"start", "middle", "end"};
    absl::StrAppendFormat(&svg_, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"%.1f\" text-anchor=\"%s\"%s fill=\"%s\">%s</text>\n",
                          x, y, size, anchors[static_cast<int>(anchor)], bold ? " font-weight=\"bold\"" : "",
                          Css(color), Escape(text));
  }
  const std::string& svg() const { return svg_; }

 private:
  std::string svg_;
};

void AppendBlock(const Paragraph& p, std::string& out) { absl::StrAppend(&out, "<p>", Escape(p.text), "</p>\n"); }

void AppendBlock(const Callout& c, std::string& out) {
  absl::StrAppend(&out, "<div class=\"callout ", ToneClass(c.tone), "\"><div class=\"headline\">", Escape(c.headline),
                  "</div><div>", Escape(c.detail), "</div></div>\n");
}

void AppendBlock(const Fields& f, std::string& out) {
  out += "<dl>\n";
  for (const auto& [label, value] : f.items) {
    absl::StrAppend(&out, "<dt>", Escape(label), "</dt><dd>", Escape(value), "</dd>\n");
  }
  out += "</dl>\n";
}

void AppendBlock(const Table& t, std::string& out) {
  out += "<table>\n<thead><tr>";
  for (const auto& h : t.header) absl::StrAppend(&out, "<th>", Escape(h), "</th>");
  out += "</tr></thead>\n<tbody>\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const Tone tone = i < t.row_tones.size() ? t.row_tones[i] : Tone::kNeutral;
    absl::StrAppend(&out, "<tr class=\"", ToneClass(tone), "\">");
    for (const auto& cell : t.rows[i]) absl::StrAppend(&out, "<td>", Escape(cell), "</td>");
    out += "</tr>\n";
  }
  out += "</tbody>\n</table>\n";
  if (!t.caption.empty()) absl::StrAppend(&out, "<p class=\"caption\">", Escape(t.caption), "</p>\n");
}

void AppendBlock(const Plot& p, std::string& out) {
  SvgCanvas canvas;
  DrawPlot(p, kPlotWidth, kPlotHeight, canvas);
  absl::StrAppendFormat(&out,
                        "<figure><svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 %.0f %.0f\" "
                        "font-family=\"Helvetica, Arial, sans-serif\" role=\"img\" aria-label=\"%s\">\n%s</svg></figure>\n",
                        kPlotWidth, kPlotHeight, Escape(p.title), canvas.svg());
}

}  // namespace

std::string RenderHtml(const Document& document) {
  std::string out;
  absl::StrAppend(&out, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n",
                  "<meta name=\"generator\" content=\"insdiag\">\n<title>", Escape(document.title), "</title>\n<style>",
                  kStyle, "</style>\n</head>\n<body>\n<header>\n<h1>", Escape(document.title),
                  "</h1>\n<p class=\"subtitle\">", Escape(document.subtitle), "</p>\n<p class=\"generated\">Generated ",
                  Escape(document.generated_at), "</p>\n</header>\n");
  for (const Section& section : document.sections) {
    absl::StrAppend(&out, "<section>\n<h2>", Escape(section.title), "</h2>\n");
    for (const Block& block : section.blocks) {
      std::visit([&out](const auto& b) { AppendBlock(b, out); }, block);
    }
    out += "</section>\n";
  }
  absl::StrAppend(&out, "<footer>", Escape(document.footer), "</footer>\n</body>\n</html>\n");
  return out;
}

}  // namespace insdiag::testreport
