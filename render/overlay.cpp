// Caption, colour bars and scale bar, drawn on the CPU onto the finished image.
//
// Text is FreeType with DejaVu Sans from Debian (fonts-dejavu-core): proper anti-aliased glyphs at
// any size and the whole of Unicode (µ, °, ², Greek) for units. A built-in bitmap font was the
// alternative: no dependency, but one size, ASCII only, and blocky at 4K.
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

#include "render/internal.h"

namespace dem::render::detail {

namespace {

using Rgb = std::array<std::uint8_t, 3>;

constexpr const char* default_font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

/// Next code point of UTF-8 text; malformed bytes come back as '?'.
char32_t next_code_point(std::string_view text, std::size_t& i) {
  const auto byte = [&](std::size_t k) { return k < text.size() ? std::uint8_t(text[k]) : 0; };
  const std::uint8_t lead = byte(i);
  int length = lead < 0x80 ? 1 : (lead >> 5) == 6 ? 2 : (lead >> 4) == 14 ? 3 : (lead >> 3) == 30 ? 4 : 0;
  if (length == 0) return ++i, U'?';
  char32_t code = length == 1 ? lead : lead & (0x7F >> length);
  for (int k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return ++i, U'?';
    code = (code << 6) | (byte(i + k) & 0x3F);
  }
  i += length;
  return code;
}

class Font {
 public:
  explicit Font(const std::string& path) {
    if (FT_Init_FreeType(&library_)) throw std::runtime_error("render: FreeType does not start");
    if (FT_New_Face(library_, path.c_str(), 0, &face_)) {
      FT_Done_FreeType(library_);
      throw std::runtime_error("render: cannot load the font " + path);
    }
  }
  ~Font() {
    FT_Done_Face(face_);
    FT_Done_FreeType(library_);
  }
  Font(const Font&) = delete;
  Font& operator=(const Font&) = delete;

  int ascent(int px) { return size(px), int(face_->size->metrics.ascender >> 6); }

  /// Draws text with its baseline at y (or only measures it when image is null); returns the width.
  int draw(Image* image, std::string_view text, int x, int y, int px, Rgb ink) {
    size(px);
    const int x0 = x;
    FT_UInt previous = 0;
    for (std::size_t i = 0; i < text.size();) {
      const FT_UInt glyph_index = FT_Get_Char_Index(face_, next_code_point(text, i));
      if (previous && glyph_index && FT_HAS_KERNING(face_)) {
        FT_Vector kerning;
        FT_Get_Kerning(face_, previous, glyph_index, FT_KERNING_DEFAULT, &kerning);
        x += int(kerning.x >> 6);
      }
      previous = glyph_index;
      if (FT_Load_Glyph(face_, glyph_index, image ? FT_LOAD_RENDER : FT_LOAD_DEFAULT)) continue;
      const FT_GlyphSlot glyph = face_->glyph;
      if (image) blend(*image, glyph->bitmap, x + glyph->bitmap_left, y - glyph->bitmap_top, ink);
      x += int(glyph->advance.x >> 6);
    }
    return x - x0;
  }
  int width(std::string_view text, int px) { return draw(nullptr, text, 0, 0, px, {}); }

 private:
  FT_Library library_ = nullptr;
  FT_Face face_ = nullptr;

  void size(int px) { FT_Set_Pixel_Sizes(face_, 0, FT_UInt(px)); }

  static void blend(Image& image, const FT_Bitmap& bitmap, int left, int top, Rgb ink) {
    for (unsigned row = 0; row < bitmap.rows; ++row)
      for (unsigned column = 0; column < bitmap.width; ++column) {
        const int x = left + int(column), y = top + int(row);
        if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
        const int alpha = bitmap.buffer[row * bitmap.pitch + column];
        std::uint8_t* p = image.pixel(x, y);
        for (int c = 0; c < 3; ++c) p[c] = std::uint8_t((p[c] * (255 - alpha) + ink[c] * alpha + 127) / 255);
      }
  }
};

/// The font, found once: $DEMDESIGN_FONT, else DejaVu Sans where Debian puts it.
Font& font() {
  static std::unique_ptr<Font> loaded;
  if (!loaded) {
    const char* chosen = std::getenv("DEMDESIGN_FONT");
    const std::string path = chosen && *chosen ? chosen : default_font;
    if (!std::filesystem::exists(path))
      throw std::runtime_error("render: no font at " + path +
                               " (install the Debian package fonts-dejavu-core or set DEMDESIGN_FONT)");
    loaded = std::make_unique<Font>(path);
  }
  return *loaded;
}

void fill(Image& image, int x0, int y0, int x1, int y1, const std::array<float, 3>& colour, float alpha) {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, image.width), y1 = std::min(y1, image.height);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      std::uint8_t* p = image.pixel(x, y);
      for (int c = 0; c < 3; ++c) p[c] = std::uint8_t(std::lround(p[c] * (1 - alpha) + 255 * colour[c] * alpha));
    }
}

std::array<float, 3> to_float(Rgb c) { return {c[0] / 255.f, c[1] / 255.f, c[2] / 255.f}; }

/// Largest 1, 2 or 5 x 10^k not above x (x > 0).
double round_down_125(double x) {
  const double decade = std::pow(10.0, std::floor(std::log10(x)));
  const double m = x / decade;
  return decade * (m >= 5 ? 5 : m >= 2 ? 2 : 1);
}

/// Number with `decimals` digits after the point, trailing zeros beyond `keep` dropped.
std::string format_fixed(double v, int decimals, int keep) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, v);
  std::string s = text;
  if (s.find('.') != std::string::npos) {
    while (decimals > keep && s.back() == '0') s.pop_back(), --decimals;
    if (s.back() == '.') s.pop_back();
  }
  return s == "-0" ? "0" : s;
}

std::string format_tick(double v, double step, double magnitude, bool end) {
  if (magnitude >= 1e5 || magnitude < 1e-3) {
    char text[64];
    std::snprintf(text, sizeof text, "%.3g", v);
    return text;
  }
  const int decimals = std::clamp(int(std::ceil(-std::log10(step) - 1e-9)), 0, 6);
  if (!end || v == 0) return format_fixed(v, decimals, decimals);
  // End labels show the exact range to three significant digits.
  const int significant = std::clamp(2 - int(std::floor(std::log10(std::abs(v)))), 0, 6);
  return format_fixed(v, std::max(decimals, significant), decimals);
}

struct Style {
  int text_px, margin, gap;
  Rgb ink;
  std::array<float, 3> panel;  // background colour, for the translucent panels behind overlays
};

/// A vertical colour bar with its title, right-aligned at x_right from y_top; returns its bottom.
int colour_bar(Image& image, Font& f, const Style& s, const ColourMap& map, const Range& range, int x_right,
               int y_top, int bar_height) {
  const int bar_width = std::max(6, s.text_px);
  const int tick = std::max(3, s.text_px / 3);
  const double span = range.max - range.min;
  const double magnitude = std::max(std::abs(range.min), std::abs(range.max));
  const double step = span > 0 ? round_down_125(span / 4) : 1;
  struct Label {
    double value;
    std::string text;
  };
  std::vector<Label> labels{{range.max, format_tick(range.max, step, magnitude, true)}};
  if (span > 0) {
    labels.push_back({range.min, format_tick(range.min, step, magnitude, true)});
    const double clearance = 1.2 * s.text_px * span / bar_height;  // keep interior labels apart
    for (double v = std::ceil(range.min / step) * step; v < range.max; v += step)
      if (v - range.min > clearance && range.max - v > clearance)
        labels.push_back({v, format_tick(v, step, magnitude, false)});
  }
  int label_width = 0;
  for (const Label& label : labels) label_width = std::max(label_width, f.width(label.text, s.text_px));
  const int title_width = map.label.empty() ? 0 : f.width(map.label, s.text_px);
  const int block_width = bar_width + tick + s.gap + label_width;
  const int x0 = x_right - block_width;
  const int title_height = map.label.empty() ? 0 : f.ascent(s.text_px) + s.gap;
  const int bar_top = y_top + title_height + s.text_px / 2;
  const int bar_bottom = bar_top + bar_height;

  const int panel_left = std::min(x0, x_right - title_width) - s.gap;
  fill(image, panel_left, y_top - s.gap, x_right + s.gap, bar_bottom + s.text_px / 2 + s.gap, s.panel, 0.75f);
  if (!map.label.empty()) f.draw(&image, map.label, x_right - title_width, y_top + f.ascent(s.text_px), s.text_px, s.ink);
  // Gradient, top = max; rows are exact colour-map samples.
  for (int y = bar_top; y < bar_bottom; ++y) {
    const double t = bar_height > 1 ? 1.0 - double(y - bar_top) / (bar_height - 1) : 0.5;
    fill(image, x0, y, x0 + bar_width, y + 1, colour_at(map.name, t), 1);
  }
  const auto ink = to_float(s.ink);
  fill(image, x0 - 1, bar_top - 1, x0 + bar_width + 1, bar_top, ink, 1);  // outline
  fill(image, x0 - 1, bar_bottom, x0 + bar_width + 1, bar_bottom + 1, ink, 1);
  fill(image, x0 - 1, bar_top, x0, bar_bottom, ink, 1);
  fill(image, x0 + bar_width, bar_top, x0 + bar_width + 1, bar_bottom, ink, 1);
  const int digit_half_height = f.ascent(s.text_px) * 3 / 8;
  for (const Label& label : labels) {
    const double t = span > 0 ? (label.value - range.min) / span : 0.5;
    const int y = bar_bottom - 1 - int(std::lround(t * (bar_height - 1)));
    fill(image, x0 + bar_width, y, x0 + bar_width + tick, y + 1, ink, 1);
    f.draw(&image, label.text, x0 + bar_width + tick + s.gap, y + digit_half_height, s.text_px, s.ink);
  }
  return bar_bottom + s.text_px / 2;
}

/// A bar of round length (1, 2 or 5 x 10^k m) at the bottom left, at most a fifth of the width.
void scale_bar(Image& image, Font& f, const Style& s, double pixels_per_metre) {
  if (!(pixels_per_metre > 0) || !std::isfinite(pixels_per_metre)) return;
  const double length = round_down_125(0.2 * image.width / pixels_per_metre);
  const int bar = int(std::lround(length * pixels_per_metre));
  char text[64];
  if (length >= 1) std::snprintf(text, sizeof text, "%g m", length);
  else if (length >= 1e-3) std::snprintf(text, sizeof text, "%g mm", length * 1e3);
  else std::snprintf(text, sizeof text, "%g \u00b5m", length * 1e6);
  const int thickness = std::max(2, s.text_px / 5);
  const int x0 = s.margin, y1 = image.height - s.margin, y0 = y1 - thickness;
  const int label_width = f.width(text, s.text_px);
  const int label_baseline = y0 - thickness - s.gap;
  fill(image, x0 - s.gap, label_baseline - f.ascent(s.text_px) - s.gap, x0 + std::max(bar, label_width) + s.gap,
       y1 + s.gap, s.panel, 0.75f);
  const auto ink = to_float(s.ink);
  fill(image, x0, y0, x0 + bar, y1, ink, 1);
  fill(image, x0, y0 - 2 * thickness, x0 + thickness, y1, ink, 1);  // end ticks
  fill(image, x0 + bar - thickness, y0 - 2 * thickness, x0 + bar, y1, ink, 1);
  f.draw(&image, text, x0 + (bar - label_width) / 2, label_baseline, s.text_px, s.ink);
}

}  // namespace

void draw_overlays(const Frame& frame, const Scene& scene, Image& image) {
  const bool particle_bar = frame.particle_colours && scene.particle_range;
  const bool mesh_bar = frame.mesh_colours && scene.mesh_range;
  if (frame.caption.empty() && !frame.scale_bar && !particle_bar && !mesh_bar) return;
  Font& f = font();
  Style s;
  s.text_px = std::max(10, image.height / 45);  // 24 px at 1080 lines
  s.margin = std::max(4, image.height / 40);
  s.gap = std::max(2, s.text_px / 4);
  const auto& bg = frame.background;
  const bool light = 0.2126 * bg[0] + 0.7152 * bg[1] + 0.0722 * bg[2] > 0.5;
  s.ink = light ? Rgb{25, 25, 25} : Rgb{240, 240, 240};
  s.panel = bg;

  if (!frame.caption.empty()) {
    const int px = s.text_px * 5 / 4, ascent = f.ascent(px);
    const int width = f.width(frame.caption, px);
    fill(image, s.margin - s.gap, s.margin - s.gap, s.margin + width + s.gap, s.margin + ascent + 2 * s.gap, s.panel,
         0.75f);
    f.draw(&image, frame.caption, s.margin, s.margin + ascent, px, s.ink);
  }
  // Colour bars stacked at the right, particles above walls.
  const int bars = int(particle_bar) + int(mesh_bar);
  if (bars > 0) {
    const int room = image.height - 2 * s.margin - bars * (3 * s.text_px + 2 * s.gap);
    const int bar_height = std::max(s.text_px, std::min(image.height * 7 / 20, room / bars - s.margin));
    int y = s.margin;
    if (particle_bar)
      y = colour_bar(image, f, s, *frame.particle_colours, *scene.particle_range, image.width - s.margin, y,
                     bar_height) + s.margin;
    if (mesh_bar)
      colour_bar(image, f, s, *frame.mesh_colours, *scene.mesh_range, image.width - s.margin, y, bar_height);
  }
  if (frame.scale_bar) scale_bar(image, f, s, scene.pixels_per_metre);
}

}  // namespace dem::render::detail
