// The standard fonts' advance widths (font_metrics.cc).
#pragma once

#include <array>

#include "insdiag/testreport/pdf_writer.h"

namespace insdiag::testreport {

// Width of WinAnsi `code` in `font`, in 1/1000 em; 0 for a code WinAnsi
// leaves undefined (and for control codes).
int GlyphWidth(PdfFont font, unsigned char code);

}  // namespace insdiag::testreport
