// Small helpers for self-contained HTML reports (escaped text, numbers, embedded images, the
// house CSS), shared by the run, sweep and calibration reports.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

namespace dem::html {

std::string esc(const std::string& text);               ///< HTML-escaped; "://" written as an entity
std::string num(double v, int sig = 4);                 ///< sig significant figures; NaN as a dash
std::string base64(const std::string& bytes);           ///< standard alphabet, padded
std::string embed_image(const std::string& path, const std::string& alt);  ///< <img> as a data URI, or a note
std::string head(const std::string& title);             ///< <!DOCTYPE ...><style>...</style></head><body>
std::string row(const std::vector<std::string>& cells, bool header = false);  ///< <tr>, numbers right-aligned
std::string now_text();

}  // namespace dem::html
