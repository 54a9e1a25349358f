// Checks of command-line values in the words of the case files' errors: the value, its unit and
// the valid range (CLI11's own Range lets nan through and words its message otherwise). A value
// refused stops the command before anything runs; CLI11 prints, for example,
// "--duration: -1 s is out of range; valid: (0, 1e+06] s".
#pragma once

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cmath>
#include <string>

namespace dem::app {

/// A number in [min, max] ((min, max] when open_min), finite; a whole number when `whole`.
inline CLI::Validator number_in(double min, double max, const std::string& unit = "", bool open_min = false, bool whole = false) {
  const std::string suffix = unit.empty() ? "" : " " + unit;
  const std::string range = fmt::format("{}{:g}, {:g}]{}", open_min ? "(" : "[", min, max, suffix);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double value = 0;
        std::size_t used = 0;
        try {
          value = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != text.size() || std::isnan(value))
          return fmt::format("'{}' is not a {}; valid: {}", text, whole ? "whole number" : "number", range);
        if (whole && value != std::floor(value)) return fmt::format("{} is not a whole number; valid: {}", text, range);
        if (!(open_min ? value > min : value >= min) || !(value <= max))
          return fmt::format("{}{} is out of range; valid: {}", text, suffix, range);
        return std::string();
      },
      range);
}

/// A whole number in [min, max].
inline CLI::Validator whole_in(double min, double max) { return number_in(min, max, "", false, true); }

}  // namespace dem::app
