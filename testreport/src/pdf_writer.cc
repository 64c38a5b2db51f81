#include "insdiag/testreport/pdf_writer.h"

#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>

#include <cmath>
#include <cstdint>

#include "font_metrics.h"

namespace insdiag::testreport {
namespace {

// The code points WinAnsi places in 128 … 159, where Latin-1 has controls.
struct Special {
  char32_t code_point;
  unsigned char code;
};
constexpr Special kWinAnsiSpecials[] = {
    {U'\u20AC', 128}, {U'\u201A', 130}, {U'\u0192', 131}, {U'\u201E', 132}, {U'\u2026', 133}, {U'\u2020', 134},
    {U'\u2021', 135}, {U'\u02C6', 136}, {U'\u2030', 137}, {U'\u0160', 138}, {U'\u2039', 139}, {U'\u0152', 140},
    {U'\u017D', 142}, {U'\u2018', 145}, {U'\u2019', 146}, {U'\u201C', 147}, {U'\u201D', 148}, {U'\u2022', 149},
    {U'\u2013', 150}, {U'\u2014', 151}, {U'\u02DC', 152}, {U'\u2122', 153}, {U'\u0161', 154}, {U'\u203A', 155},
    {U'\u0153', 156}, {U'\u017E', 158}, {U'\u0178', 159},
};

// Spellings of what the reports write and WinAnsi lacks: the statistics'
// Greek letters and a few mathematical signs. A reader understands
// "gamma²" where a "?" would lose the meaning.
struct Spelling {
  char32_t code_point;
  const char* text;
};
constexpr Spelling kSpellings[] = {
    {U'α', "alpha"}, {U'β', "beta"},  {U'γ', "gamma"}, {U'δ', "delta"}, {U'Δ', "Delta"}, {U'ε', "epsilon"},
    {U'η', "eta"},   {U'θ', "theta"}, {U'λ', "lambda"}, {U'ν', "nu"},   {U'π', "pi"},    {U'ρ', "rho"},
    {U'σ', "sigma"}, {U'Σ', "Sigma"}, {U'τ', "tau"},   {U'φ', "phi"},   {U'χ', "chi"},   {U'ψ', "psi"},
    {U'ω', "omega"}, {U'Ω', "Omega"}, {U'−', "-"},     {U'√', "sqrt"},  {U'≤', "<="},    {U'≥', ">="},
    {U'≈', "~"},     {U'≠', "!="},    {U'→', "->"},    {U'←', "<-"},    {U'∞', "inf"},   {U'⁻', "-"},
    {U'₀', "0"},     {U'₁', "1"},     {U'₂', "2"},     {U'₃', "3"},     {U'ᵀ', "T"},     {U'…', "..."},
};

// The next code point of `s` from `at` (advanced past it); U+FFFD for a
// malformed or truncated sequence, of which one byte is consumed.
char32_t NextCodePoint(std::string_view s, std::size_t& at) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(s[i]); };
  const unsigned char lead = byte(at);
  int extra = 0;
  char32_t cp = 0;
  if (lead < 0x80) {
    ++at;
    return lead;
  } else if ((lead & 0xE0) == 0xC0) {
    extra = 1, cp = lead & 0x1F;
  } else if ((lead & 0xF0) == 0xE0) {
    extra = 2, cp = lead & 0x0F;
  } else if ((lead & 0xF8) == 0xF0) {
    extra = 3, cp = lead & 0x07;
  } else {
    ++at;
    return U'\uFFFD';
  }
  if (at + static_cast<std::size_t>(extra) >= s.size()) {
    ++at;
    return U'\uFFFD';
  }
  for (int i = 1; i <= extra; ++i) {
    if ((byte(at + static_cast<std::size_t>(i)) & 0xC0) != 0x80) {
      ++at;
      return U'\uFFFD';
    }
    cp = (cp << 6) | (byte(at + static_cast<std::size_t>(i)) & 0x3F);
  }
  at += static_cast<std::size_t>(extra) + 1;
  return cp;
}

void AppendWinAnsi(char32_t cp, std::string& out) {
  if (cp == U'\t' || cp == U'\n' || cp == U'\r') {
    out += ' ';
    return;
  }
  if ((cp >= 0x20 && cp < 0x7F) || (cp >= 0xA0 && cp <= 0xFF)) {
    out += static_cast<char>(cp);
    return;
  }
  for (const Special& s : kWinAnsiSpecials) {
    if (s.code_point == cp) {
      out += static_cast<char>(s.code);
      return;
    }
  }
  for (const Spelling& s : kSpellings) {
    if (s.code_point == cp) {
      out += s.text;
      return;
    }
  }
  out += '?';
}

// A coordinate or width in a content stream: two decimals are 1/7200 in,
// far below what a printer resolves; trailing zeros dropped.
std::string Num(double v) {
  if (!std::isfinite(v)) v = 0.0;
  std::string s = absl::StrFormat("%.2f", v);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

std::string Rgb(const PdfColor& c) { return absl::StrCat(Num(c.r), " ", Num(c.g), " ", Num(c.b)); }

std::string Dash(double dash_pt) { return dash_pt > 0 ? absl::StrCat("[", Num(dash_pt), "] 0 d ") : ""; }

const char* FontResource(PdfFont font) { return font == PdfFont::kHelveticaBold ? "/F2" : "/F1"; }

}  // namespace

std::string ToWinAnsi(std::string_view utf8) {
  std::string out;
  out.reserve(utf8.size());
  for (std::size_t at = 0; at < utf8.size();) AppendWinAnsi(NextCodePoint(utf8, at), out);
  return out;
}

std::string EscapePdfString(std::string_view win_ansi) {
  std::string out;
  out.reserve(win_ansi.size());
  for (const char c : win_ansi) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '(' || c == ')' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || byte >= 0x7F) {
      absl::StrAppendFormat(&out, "\\%03o", byte);
    } else {
      out += c;
    }
  }
  return out;
}

double TextWidthPt(std::string_view utf8, PdfFont font, double size_pt) {
  int units = 0;
  for (const char c : ToWinAnsi(utf8)) units += GlyphWidth(font, static_cast<unsigned char>(c));
  return units * size_pt / 1000.0;
}

void PdfPage::Text(double x_pt, double y_pt, double size_pt, PdfFont font, std::string_view utf8, PdfColor color) {
  absl::StrAppend(&content_, "BT ", FontResource(font), " ", Num(size_pt), " Tf ", Rgb(color), " rg ", Num(x_pt), " ",
                  Num(y_pt), " Td (", EscapePdfString(ToWinAnsi(utf8)), ") Tj ET\n");
}

void PdfPage::Line(double x0_pt, double y0_pt, double x1_pt, double y1_pt, double width_pt, PdfColor color,
                   double dash_pt) {
  const std::pair<double, double> points[] = {{x0_pt, y0_pt}, {x1_pt, y1_pt}};
  Polyline(points, width_pt, color, dash_pt);
}

void PdfPage::Polyline(std::span<const std::pair<double, double>> points_pt, double width_pt, PdfColor color,
                       double dash_pt) {
  std::string path;
  bool pen_down = false;
  int segments = 0;
  for (const auto& [x, y] : points_pt) {
    if (!std::isfinite(x) || !std::isfinite(y)) {
      pen_down = false;
      continue;
    }
    absl::StrAppend(&path, Num(x), " ", Num(y), pen_down ? " l\n" : " m\n");
    segments += pen_down ? 1 : 0;
    pen_down = true;
  }
  if (segments == 0) return;  // a path of lone points strokes nothing
  absl::StrAppend(&content_, "q ", Num(width_pt), " w 1 J 1 j ", Dash(dash_pt), Rgb(color), " RG\n", path, "S Q\n");
}

void PdfPage::FillRect(double x_pt, double y_pt, double width_pt, double height_pt, PdfColor color) {
  absl::StrAppend(&content_, "q ", Rgb(color), " rg ", Num(x_pt), " ", Num(y_pt), " ", Num(width_pt), " ",
                  Num(height_pt), " re f Q\n");
}

PdfPage& PdfDocument::AddPage() { return pages_.emplace_back(); }

std::string PdfDocument::Serialize(const PdfInfo& info) const {
  // Objects: 1 catalog, 2 page tree, 3 and 4 the fonts, 5 the information
  // dictionary, then each page and its content stream.
  constexpr int kFirstPageObject = 6;
  std::vector<std::string> objects;
  std::string kids;
  for (std::size_t i = 0; i < pages_.size(); ++i) {
    absl::StrAppend(&kids, i > 0 ? " " : "", kFirstPageObject + 2 * static_cast<int>(i), " 0 R");
  }
  objects.push_back("<< /Type /Catalog /Pages 2 0 R >>");
  objects.push_back(absl::StrCat("<< /Type /Pages /Kids [", kids, "] /Count ", pages_.size(), " >>"));
  objects.push_back("<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica /Encoding /WinAnsiEncoding >>");
  objects.push_back("<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica-Bold /Encoding /WinAnsiEncoding >>");
  std::string info_dict = absl::StrCat("<< /Producer (insdiag) /Title (", EscapePdfString(ToWinAnsi(info.title)),
                                       ") /Subject (", EscapePdfString(ToWinAnsi(info.subject)), ")");
  if (!info.creation_date.empty()) {
    absl::StrAppend(&info_dict, " /CreationDate (", EscapePdfString(info.creation_date), ")");
  }
  objects.push_back(info_dict + " >>");
  for (std::size_t i = 0; i < pages_.size(); ++i) {
    objects.push_back(absl::StrCat("<< /Type /Page /Parent 2 0 R /MediaBox [0 0 ", Num(page_width_pt_), " ",
                                   Num(page_height_pt_),
                                   "] /Resources << /Font << /F1 3 0 R /F2 4 0 R >> >> /Contents ",
                                   kFirstPageObject + 2 * static_cast<int>(i) + 1, " 0 R >>"));
    const std::string& content = pages_[i].content();
    objects.push_back(absl::StrCat("<< /Length ", content.size(), " >>\nstream\n", content, "\nendstream"));
  }

  // The header's second line holds bytes above 127, so that file transfers
  // treat the file as binary (§7.5.2).
  std::string file = "%PDF-1.4\n%\xE2\xE3\xCF\xD3\n";
  std::vector<std::size_t> offsets;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    offsets.push_back(file.size());
    absl::StrAppend(&file, i + 1, " 0 obj\n", objects[i], "\nendobj\n");
  }
  const std::size_t xref_at = file.size();
  // Each entry is exactly 20 bytes, its end of line included (§7.5.4).
  absl::StrAppend(&file, "xref\n0 ", objects.size() + 1, "\n0000000000 65535 f \n");
  for (const std::size_t offset : offsets) absl::StrAppendFormat(&file, "%010u 00000 n \n", offset);
  absl::StrAppend(&file, "trailer\n<< /Size ", objects.size() + 1, " /Root 1 0 R /Info 5 0 R >>\nstartxref\n", xref_at,
                  "\n%%EOF\n");
  return file;
}

}  // namespace insdiag::testreport
