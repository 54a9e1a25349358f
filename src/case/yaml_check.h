// Checked reading of YAML maps: every key is looked up by name, every value is range-checked,
// and keys nobody asked for are errors that suggest the nearest valid key. Messages name the
// file, line, column and the full key path ("materials.glass.restitution").
#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "case/spec.h"

namespace dem {

/// Parses YAML `text` read from `file` (the name errors give). Throws CaseError naming the file,
/// line and column when the text is not valid YAML, or when a map holds a key twice: YAML does
/// not allow it, and yaml-cpp would keep the first value without a word.
YAML::Node parse_yaml(const std::string& text, const std::string& file);
/// Reads the file at `path` and parses it as parse_yaml(); `what` names it in the error when it
/// cannot be opened ("the case file").
YAML::Node read_yaml_file(const std::string& path, const std::string& what);

/// The valid word closest to `word` (edit distance), or "" when none is close.
std::string nearest_word(std::string_view word, const std::vector<std::string>& valid);

/// One key a MapReader was asked for, as `demdesign keys` records it to write the case-key
/// reference (docs/case-keys.md) from the readers themselves.
struct KeyRequest {
  std::string file;      ///< the file being read
  std::string map_path;  ///< key path of the map ("" at the top), list indices as in the file
  std::string key;
  std::string names;     ///< when the map's keys are names (MapReader::keys_are_names): what they name
  std::string kind;      ///< number, integer, boolean, word, text, vector, section
  bool required = false;
  std::string fallback;  ///< the default as text ("" when none)
  std::optional<double> min, max;
  std::string unit;
  std::vector<std::string> allowed;
  std::string value;     ///< the value in the file as written; "" when absent or not a scalar
  std::string shape;     ///< of a section's value: map, list or value; "" when absent
};

/// Receives every key request of the MapReaders of its thread while it is set.
class KeyRecorder {
 public:
  virtual ~KeyRecorder() = default;
  virtual void record(KeyRequest request) = 0;
};

/// Sets this thread's recorder (nullptr, the default: nothing is recorded); returns the previous
/// one. Only `demdesign keys` sets one: it is a parse-time hook, never in a simulation's loops.
KeyRecorder* set_key_recorder(KeyRecorder* recorder);

class MapReader {
 public:
  /// `path` is the key path of this map ("" at the top). Throws CaseError unless a map.
  MapReader(const YAML::Node& node, std::string file, std::string path);

  bool has(const std::string& key) const;
  SourceLocation where(const std::string& key) const;  ///< of the value, or of the map
  SourceLocation location() const { return at(node_); }
  std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  /// A number in [min, max]; `fallback` when absent.
  double number(const std::string& key, double fallback, double min, double max, std::string_view unit = "");
  /// A number that must be given.
  double required_number(const std::string& key, double min, double max, std::string_view unit = "");
  int64_t integer(const std::string& key, int64_t fallback, int64_t min, int64_t max);
  bool boolean(const std::string& key, bool fallback);
  /// A string that must be given; `what` says what it should name. When `allowed` is not empty
  /// it must be one of them.
  std::string required_string(const std::string& key, const std::string& what, const std::vector<std::string>& allowed = {});
  /// A string; when `allowed` is not empty it must be one of them.
  std::string string(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed = {});
  Vec3 vec3(const std::string& key, const Vec3& fallback);
  /// The raw node (marks the key used); empty node when absent.
  YAML::Node node(const std::string& key);
  /// All keys, in file order.
  std::vector<std::string> keys() const;
  /// Says that this map's keys are names the user chooses (mesh names, parameter names, key
  /// paths), not keys of the format; `what` stands for them in the key reference ("MESH").
  void keys_are_names(std::string what) { names_ = std::move(what); }

  /// Error for a value of `key`, with location.
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  /// Throws for every key not read, naming the nearest of `valid` (or of the keys read).
  void finish(const std::vector<std::string>& extra_valid = {}) const;

  const std::string& file() const { return file_; }

  SourceLocation at(const YAML::Node& n) const;
  /// A number (NaN refused; "inf", ".inf" and "rigid" give +infinity).
  static double scalar_number(const YAML::Node& n, const MapReader& ctx, const std::string& key);
  /// A finite number (coordinates, indices, list entries).
  static double finite_number(const YAML::Node& n, const MapReader& ctx, const std::string& key);

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
  mutable std::set<std::string> used_;
  std::string names_;  ///< see keys_are_names

  /// Passes a request to this thread's KeyRecorder, if one is set.
  void record(const std::string& key, std::string_view kind, bool required, std::string fallback,
              std::optional<double> min = {}, std::optional<double> max = {}, std::string_view unit = "",
              const std::vector<std::string>& allowed = {}) const;
  double read_number(const std::string& key, double fallback, double min, double max, std::string_view unit);
  std::string read_string(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed);
};

}  // namespace dem
