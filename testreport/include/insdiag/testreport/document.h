// A report as a sequence of sections of neutral blocks — text, labelled
// fields, tables, plots — that one builder fills (test_report.h) and two
// renderers lay out: as HTML with inline SVG, and as PDF. What the report
// says is decided once, here; how it looks, in each renderer.
#pragma once

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace insdiag::testreport {

// How a block or a row should strike the reader.
enum class Tone { kNeutral, kGood, kWarning, kBad };

struct Paragraph {
  std::string text;
};

// The statement the document exists for (the verdict): large, toned.
struct Callout {
  std::string headline;
  std::string detail;
  Tone tone = Tone::kNeutral;
};

// "label: value" lines.
struct Fields {
  std::vector<std::pair<std::string, std::string>> items;
};

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  // each as wide as `header`
  std::vector<Tone> row_tones;                 // empty, or one per row
  std::string caption;                         // under the table; may be empty
};

// A series' colour: an index into the renderers' shared palette (plot_drawing.h).
enum class SeriesColor { kData, kBand, kFit, kSecond, kThird };

struct PlotSeries {
  std::string label;  // in the legend; empty: not in the legend
  std::vector<double> x;
  std::vector<double> y;  // as long as x; a non-finite value breaks the line
  SeriesColor color = SeriesColor::kData;
  bool dashed = false;
};

struct Plot {
  std::string title;
  std::string x_label;  // with its unit, "time [s]"
  std::string y_label;
  bool log_x = false;
  bool log_y = false;
  std::vector<PlotSeries> series;
  // Spans of x shaded behind the data (where the model fails).
  std::vector<std::pair<double, double>> shaded_x;
};

using Block = std::variant<Paragraph, Callout, Fields, Table, Plot>;

struct Section {
  std::string title;
  std::vector<Block> blocks;
};

struct Document {
  std::string title;
  std::string subtitle;
  std::string footer;  // on every PDF page, at the end of the HTML
  std::string generated_at;  // RFC 3339, UTC
  std::vector<Section> sections;
};

}  // namespace insdiag::testreport
