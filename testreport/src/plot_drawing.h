// A plot drawn once for both renderers: axes with ticks, grid, shaded
// spans, series and legend, onto an abstract canvas that the HTML renderer
// turns into SVG elements and the PDF renderer into content-stream
// operators.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "insdiag/testreport/document.h"

namespace insdiag::testreport {

struct Rgb {
  double r = 0.0;  // 0 … 1
  double g = 0.0;
  double b = 0.0;
};

Rgb ColorOf(SeriesColor color);

enum class Anchor { kStart, kMiddle, kEnd };

// Coordinates from the drawing's top-left corner, y down, in the
// renderer's unit (points in PDF, CSS pixels in SVG).
class Canvas {
 public:
  virtual ~Canvas() = default;
  virtual void Polyline(const std::vector<std::pair<double, double>>& points, double width, Rgb color,
                        bool dashed) = 0;
  virtual void Rect(double x, double y, double width, double height, Rgb fill) = 0;
  // `y` is the text's baseline.
  virtual void Text(double x, double y, double size, Anchor anchor, bool bold, const std::string& text, Rgb color) = 0;
};

// The width of `text` in Helvetica at `size` (the fonts both renderers use).
double TextWidth(const std::string& text, double size, bool bold);

// Draws `plot` into the box [0, width] × [0, height] of `canvas`.
void DrawPlot(const Plot& plot, double width, double height, Canvas& canvas);

}  // namespace insdiag::testreport
