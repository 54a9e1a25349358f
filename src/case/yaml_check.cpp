#include "case/yaml_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace dem {

std::string SourceLocation::str() const {
  if (line <= 0) return file;
  return fmt::format("{}:{}:{}", file, line, column);
}

namespace {

size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

/// Throws on the first map (depth first, in file order) that holds a scalar key twice. `path`
/// holds the key path of `node` a step an entry ("materials", "[0]"), joined only for the message.
void refuse_duplicate_keys(const YAML::Node& node, const std::string& file, std::vector<std::string>& path) {
  if (node.IsSequence()) {
    for (size_t k = 0; k < node.size(); ++k) {
      path.push_back(fmt::format("[{}]", k));
      refuse_duplicate_keys(node[k], file, path);
      path.pop_back();
    }
    return;
  }
  if (!node.IsMap()) return;
  std::unordered_map<std::string, YAML::Mark> seen;
  for (const auto& kv : node) {
    if (!kv.first.IsScalar()) continue;
    const std::string& key = kv.first.Scalar();
    path.push_back(key);
    const auto [first, fresh] = seen.emplace(key, kv.first.Mark());
    if (!fresh) {
      std::string key_path;
      for (const std::string& step : path) key_path += (key_path.empty() || step.front() == '[' ? "" : ".") + step;
      throw CaseError(fmt::format("{}:{}:{}: {}: given twice in one map (first at line {}); a key may appear once: remove one or merge them",
                                  file, kv.first.Mark().line + 1, kv.first.Mark().column + 1, key_path, first->second.line + 1));
    }
    refuse_duplicate_keys(kv.second, file, path);
    path.pop_back();
  }
}

}  // namespace

YAML::Node parse_yaml(const std::string& text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw CaseError(fmt::format("{}:{}:{}: not valid YAML: {}", file, e.mark.line + 1, e.mark.column + 1, e.msg));
  }
  std::vector<std::string> path;
  refuse_duplicate_keys(root, file, path);
  return root;
}

YAML::Node read_yaml_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw CaseError(fmt::format("{}: cannot open {}", path, what));
  std::stringstream text;
  text << in.rdbuf();
  return parse_yaml(text.str(), path);
}

namespace {

std::string format_range(double min, double max) {
  return fmt::format("[{:g}, {:g}]", min, max);
}

thread_local KeyRecorder* key_recorder = nullptr;

}  // namespace

KeyRecorder* set_key_recorder(KeyRecorder* recorder) {
  KeyRecorder* previous = key_recorder;
  key_recorder = recorder;
  return previous;
}

void MapReader::record(const std::string& key, std::string_view kind, bool required, std::string fallback,
                       std::optional<double> min, std::optional<double> max, std::string_view unit,
                       const std::vector<std::string>& allowed) const {
  if (!key_recorder) return;
  KeyRequest r;
  r.file = file_, r.map_path = path_, r.key = key, r.names = names_, r.kind = kind, r.required = required;
  r.fallback = std::move(fallback), r.min = min, r.max = max, r.unit = unit, r.allowed = allowed;
  if (const YAML::Node n = node_[key]) {
    r.shape = n.IsMap() ? "map" : n.IsSequence() ? "list" : "value";
    if (n.IsScalar()) {
      r.value = n.Scalar();
    } else if (n.IsSequence() && n.size() <= 4) {  // a short list of scalars: a vector, a pair
      std::string items;
      for (const auto& item : n) {
        if (!item.IsScalar()) return key_recorder->record(std::move(r));
        items += (items.empty() ? "" : ", ") + item.Scalar();
      }
      r.value = "[" + items + "]";
    }
  }
  key_recorder->record(std::move(r));
}

std::string nearest_word(std::string_view word, const std::vector<std::string>& valid) {
  std::string best;
  size_t best_distance = std::numeric_limits<size_t>::max();
  for (const auto& v : valid) {
    const size_t d = edit_distance(word, v);
    if (d < best_distance) best_distance = d, best = v;
  }
  // Close enough to be a typo: at most a third of the word wrong.
  if (best_distance <= std::max<size_t>(2, word.size() / 3)) return best;
  return "";
}

MapReader::MapReader(const YAML::Node& node, std::string file, std::string path)
    : node_(node), file_(std::move(file)), path_(std::move(path)) {
  if (!node_.IsMap()) {
    throw CaseError(fmt::format("{}: '{}' must be a map of keys to values", at(node_).str(),
                                path_.empty() ? "the case" : path_));
  }
}

SourceLocation MapReader::at(const YAML::Node& n) const {
  const YAML::Mark mark = n.Mark();
  if (mark.is_null()) return {file_, 0, 0};
  return {file_, mark.line + 1, mark.column + 1};
}

bool MapReader::has(const std::string& key) const { return static_cast<bool>(node_[key]); }

SourceLocation MapReader::where(const std::string& key) const {
  const YAML::Node n = node_[key];
  return n ? at(n) : at(node_);
}

std::vector<std::string> MapReader::keys() const {
  std::vector<std::string> out;
  for (const auto& kv : node_) out.push_back(kv.first.as<std::string>());
  return out;
}

void MapReader::fail(const std::string& key, const std::string& message) const {
  throw CaseError(fmt::format("{}: {}: {}", where(key).str(), key_path(key), message));
}

double MapReader::scalar_number(const YAML::Node& n, const MapReader& ctx, const std::string& key) {
  if (!n.IsScalar()) ctx.fail(key, "must be a number");
  const std::string text = n.Scalar();
  if (text == "rigid" || text == "inf" || text == ".inf") return std::numeric_limits<double>::infinity();
  try {
    size_t used = 0;
    const double value = std::stod(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    if (std::isnan(value)) throw std::invalid_argument(text);  // NaN is never a valid input
    return value;
  } catch (const std::exception&) {
    ctx.fail(key, fmt::format("'{}' is not a number", text));
  }
}

double MapReader::finite_number(const YAML::Node& n, const MapReader& ctx, const std::string& key) {
  const double value = scalar_number(n, ctx, key);
  if (!std::isfinite(value)) ctx.fail(key, fmt::format("'{}' must be a finite number", n.Scalar()));
  return value;
}

double MapReader::read_number(const std::string& key, double fallback, double min, double max, std::string_view unit) {
  used_.insert(key);
  const YAML::Node n = node_[key];
  if (!n) return fallback;
  const double value = scalar_number(n, *this, key);
  if (std::isnan(value) || value < min || value > max) {
    fail(key, fmt::format("{:g}{}{} is out of range; valid: {}{}", value, unit.empty() ? "" : " ", unit,
                          format_range(min, max), unit.empty() ? "" : fmt::format(" {}", unit)));
  }
  return value;
}

double MapReader::number(const std::string& key, double fallback, double min, double max, std::string_view unit) {
  record(key, "number", false, fmt::format("{:g}", fallback), min, max, unit);
  return read_number(key, fallback, min, max, unit);
}

double MapReader::required_number(const std::string& key, double min, double max, std::string_view unit) {
  record(key, "number", true, "", min, max, unit);
  if (!has(key)) {
    throw CaseError(fmt::format("{}: {}: missing; give a number in {}{}", at(node_).str(), key_path(key),
                                format_range(min, max), unit.empty() ? "" : fmt::format(" {}", unit)));
  }
  return read_number(key, 0.0, min, max, unit);
}

int64_t MapReader::integer(const std::string& key, int64_t fallback, int64_t min, int64_t max) {
  record(key, "integer", false, fmt::format("{}", fallback), static_cast<double>(min), static_cast<double>(max));
  const double value = read_number(key, static_cast<double>(fallback), static_cast<double>(min), static_cast<double>(max), "");
  if (value != std::floor(value)) fail(key, fmt::format("{:g} must be a whole number", value));
  return static_cast<int64_t>(value);
}

bool MapReader::boolean(const std::string& key, bool fallback) {
  record(key, "boolean", false, fallback ? "true" : "false");
  used_.insert(key);
  const YAML::Node n = node_[key];
  if (!n) return fallback;
  const std::string text = n.IsScalar() ? n.Scalar() : "";
  if (text == "true" || text == "yes" || text == "on") return true;
  if (text == "false" || text == "no" || text == "off") return false;
  fail(key, fmt::format("'{}' must be true or false", text));
}

std::string MapReader::string(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed) {
  record(key, allowed.empty() ? "text" : "word", false, fallback, {}, {}, "", allowed);
  return read_string(key, fallback, allowed);
}

std::string MapReader::read_string(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed) {
  used_.insert(key);
  const YAML::Node n = node_[key];
  if (!n) return fallback;
  if (!n.IsScalar()) fail(key, "must be a single word or text");
  const std::string value = n.Scalar();
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), value) == allowed.end()) {
    const std::string hint = nearest_word(value, allowed);
    fail(key, fmt::format("'{}' is not valid{}; valid: {}", value,
                          hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), join(allowed)));
  }
  return value;
}

std::string MapReader::required_string(const std::string& key, const std::string& what, const std::vector<std::string>& allowed) {
  record(key, allowed.empty() ? "text" : "word", true, "", {}, {}, "", allowed);
  const std::string value = read_string(key, "", allowed);
  if (value.empty()) fail(key, "missing: " + what);
  return value;
}

Vec3 MapReader::vec3(const std::string& key, const Vec3& fallback) {
  record(key, "vector", false, fmt::format("[{:g}, {:g}, {:g}]", fallback.x(), fallback.y(), fallback.z()));
  used_.insert(key);
  const YAML::Node n = node_[key];
  if (!n) return fallback;
  if (!n.IsSequence() || n.size() != 3) fail(key, "must be a list of three numbers, e.g. [0, 0, -9.81]");
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    v[k] = scalar_number(n[k], *this, key);
    if (!std::isfinite(v[k])) fail(key, "components must be finite numbers");
  }
  return v;
}

YAML::Node MapReader::node(const std::string& key) {
  record(key, "section", false, "");
  used_.insert(key);
  return node_[key];
}

void MapReader::finish(const std::vector<std::string>& extra_valid) const {
  std::vector<std::string> valid(used_.begin(), used_.end());
  valid.insert(valid.end(), extra_valid.begin(), extra_valid.end());
  std::sort(valid.begin(), valid.end());
  valid.erase(std::unique(valid.begin(), valid.end()), valid.end());  // a key read here and also passed as valid is listed once
  for (const auto& kv : node_) {
    const std::string key = kv.first.as<std::string>();
    if (used_.count(key) || std::find(extra_valid.begin(), extra_valid.end(), key) != extra_valid.end()) continue;
    const std::string hint = nearest_word(key, valid);
    throw CaseError(fmt::format("{}: {}: unknown key{}; valid keys here: {}", at(kv.first).str(), key_path(key),
                                hint.empty() ? "" : fmt::format(" (did you mean '{}'?)", hint), join(valid)));
  }
}

}  // namespace dem
