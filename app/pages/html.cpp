#include "pages/html.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace dem::html {

std::string esc(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else if (c == '\'') out += "&#39;";
    else if (c == '/' && i > 0 && text[i - 1] == ':') out += "&#47;";
    else out += c;
  }
  return out;
}

std::string num(double v, int sig) {
  if (std::isnan(v)) return "&ndash;";
  if (std::isinf(v)) return v > 0 ? "&infin;" : "&minus;&infin;";
  if (v == 0) return "0";
  const double magnitude = std::abs(v);
  if (magnitude < 1e-3 || magnitude >= 1e7) return fmt::format("{:.{}e}", v, sig - 1);
  const int decimals = std::max(0, sig - 1 - static_cast<int>(std::floor(std::log10(magnitude))));
  return fmt::format("{:.{}f}", v, decimals);
}

std::string base64(const std::string& bytes) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8 | (unsigned char)bytes[i + 2];
    out += table[v >> 18 & 63], out += table[v >> 12 & 63], out += table[v >> 6 & 63], out += table[v & 63];
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = (unsigned char)bytes[i] << 16;
    out += table[v >> 18 & 63], out += table[v >> 12 & 63], out += "==";
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8;
    out += table[v >> 18 & 63], out += table[v >> 12 & 63], out += table[v >> 6 & 63], out += '=';
  }
  return out;
}

namespace {
const char* kStyle = R"(
body{font-family:"DejaVu Sans",Helvetica,Arial,sans-serif;font-size:14px;color:#222;max-width:1100px;margin:24px auto;padding:0 16px;line-height:1.45}
h1{font-size:24px;margin-bottom:4px}h2{font-size:19px;border-bottom:2px solid #ccd;padding-bottom:3px;margin-top:32px}
h3{font-size:15px;margin-bottom:6px}
table{border-collapse:collapse;margin:8px 0 14px}th,td{border:1px solid #ccd;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#eef0f6}td.n{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.meta{color:#555}.note{color:#555;font-size:13px}
.banner{padding:10px 14px;margin:12px 0;border-radius:4px;font-weight:bold}
.bad{background:#fbe3e1;border:1px solid #d9534f}.warn{background:#fff4d6;border:1px solid #e0a800}.good{background:#e3f4e1;border:1px solid #4c9a47}
.missing{background:#f4f4f4;border:1px dashed #999;padding:10px;color:#555}
img{max-width:100%;border:1px solid #ddd}figure{margin:10px 0 18px}figcaption{font-size:13px;color:#555}
pre{background:#f6f7f9;border:1px solid #dde;padding:8px;overflow-x:auto;font-size:12px}
.grid{display:flex;flex-wrap:wrap;gap:12px}.grid figure{flex:1 1 320px;max-width:48%}
)";

bool looks_numeric(const std::string& cell) {
  if (cell.empty()) return false;
  if (std::isdigit(static_cast<unsigned char>(cell[0])) || ((cell[0] == '-' || cell[0] == '+') && cell.size() > 1 && std::isdigit(static_cast<unsigned char>(cell[1]))))
    return true;
  return cell.rfind("&ndash;", 0) == 0 || cell.rfind("&minus;", 0) == 0 || cell.rfind("&infin;", 0) == 0;
}
}  // namespace

std::string embed_image(const std::string& path, const std::string& alt) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return fmt::format("<p class=\"missing\">image not available: {}</p>", esc(path));
  std::stringstream bytes;
  bytes << in.rdbuf();
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  const char* mime = ext == ".jpg" || ext == ".jpeg" ? "image/jpeg" : ext == ".svg" ? "image/svg+xml" : "image/png";
  return fmt::format("<img alt=\"{}\" src=\"data:{};base64,{}\">", esc(alt), mime, base64(bytes.str()));
}

std::string head(const std::string& title) {
  return fmt::format("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>{}</title>\n<style>{}</style>\n</head><body>\n", esc(title), kStyle);
}

std::string row(const std::vector<std::string>& cells, bool header) {
  std::string out = "<tr>";
  bool first = true;
  for (const std::string& c : cells) {
    if (header) out += "<th>" + c + "</th>";
    else out += (!first && looks_numeric(c) ? "<td class=\"n\">" : "<td>") + c + "</td>";
    first = false;
  }
  return out + "</tr>\n";
}

std::string now_text() {
  const std::time_t t = std::time(nullptr);
  std::tm local{};
  localtime_r(&t, &local);
  char buffer[64];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d %H:%M %Z", &local);
  return buffer;
}

}  // namespace dem::html
