// The case-key reference: the shipped files read with a KeyRecorder set, the requests turned
// into one table per section. Rejected alternative: a hand-written list of keys beside the
// readers; it drifts the first time someone adds a key and forgets the list.
#include "cli/case_keys.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "case/spec.h"
#include "case/yaml_check.h"
#include "contact/effect.h"
#include "equipment.h"
#include "model/library.h"
#include "model/material_model.h"
#include "lab/measurements.h"
#include "campaign/sweep.h"

namespace dem::app {

namespace {

namespace fs = std::filesystem;

enum class Document { case_file, material_file, measurement_file, none };

/// Collects every request of the readers while it is installed on this thread.
class Collector : public KeyRecorder {
 public:
  Collector() : previous_(set_key_recorder(this)) {}
  ~Collector() override { set_key_recorder(previous_); }
  Collector(const Collector&) = delete;
  Collector& operator=(const Collector&) = delete;
  void record(KeyRequest request) override { requests.push_back(std::move(request)); }

  std::vector<KeyRequest> requests;

 private:
  KeyRecorder* previous_;
};

std::vector<fs::path> yaml_files(const fs::path& folder) {
  std::vector<fs::path> out;
  if (!fs::is_directory(folder)) return out;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.is_regular_file() && entry.path().extension() == ".yaml") out.push_back(entry.path().lexically_normal());
  std::sort(out.begin(), out.end());
  return out;
}

/// What the shipped files are, by their top-level keys: a case has `simulation`, a material file
/// `properties`, a measurement file `experiments`.
Document kind_of(const fs::path& file) {
  const YAML::Node root = YAML::LoadFile(file.string());
  if (!root.IsMap()) return Document::none;
  if (root["simulation"]) return Document::case_file;
  if (root["properties"]) return Document::material_file;
  if (root["experiments"]) return Document::measurement_file;
  return Document::none;
}

/// A number as the tables show it: shortest form, and "inf" for the "no limit" sentinels.
std::string shown_number(double value) {
  if (value >= 1e299) return "inf";
  if (value <= -1e299) return "-inf";
  return fmt::format("{:.10g}", value);
}

std::string shown_fallback(const KeyRequest& r) {
  if (r.required) return "required";
  if (r.kind == "section") return "";
  if (r.kind == "number" && (r.fallback == "1e+300" || r.fallback == "inf")) return "inf";
  if (r.fallback.empty()) return "none";
  return r.fallback;
}

std::string shown_range(const KeyRequest& r) {
  if (r.min && r.max) return fmt::format("[{}, {}]", shown_number(*r.min), shown_number(*r.max));
  std::string words;
  for (const std::string& w : r.allowed) words += (words.empty() ? "" : ", ") + w;
  return words;
}

std::string shown_kind(const std::string& kind) {
  if (kind == "integer") return "whole number";
  if (kind == "boolean") return "true/false";
  if (kind == "vector") return "[x, y, z]";
  return kind;
}

/// The parts of a key path: "inlets[0].diameter" -> {"inlets[0]", "diameter"}.
std::pair<std::string, std::string> split_last(const std::string& path) {
  const size_t dot = path.rfind('.');
  if (dot == std::string::npos) return {"", path};
  return {path.substr(0, dot), path.substr(dot + 1)};
}

std::string without_index(const std::string& segment) { return segment.substr(0, segment.find('[')); }
bool has_index(const std::string& segment) { return segment.find('[') != std::string::npos; }

void add_unique(std::vector<std::string>& list, const std::string& value) {
  if (std::find(list.begin(), list.end(), value) == list.end()) list.push_back(value);
}

/// One key of the reference, merged over every request for it.
struct Row {
  std::string key;
  std::vector<std::string> kinds, shapes, fallbacks, ranges;
  std::string unit;
  std::string example, example_file;
  bool contact_parameter = false;  ///< stands for every parameter of the contact-parameter table
};

struct Section {
  std::string title;
  std::vector<Row> rows;
};

/// The requests of one kind of document turned into rows: list indices collapse to `[]`, a map
/// level whose keys nobody asked for by name (materials.gravel, clumps.trio) becomes NAME, the
/// keys of a map whose keys are names become what they name (MESH, PARAMETER, ...), and the
/// contact parameters of a material or pair map become one CONTACT_PARAMETER row.
class Normaliser {
 public:
  explicit Normaliser(const std::vector<const KeyRequest*>& requests) {
    // Map paths by depth, so that a map's parent is named before the map.
    std::vector<std::string> paths;
    for (const KeyRequest* r : requests) add_unique(paths, r->map_path);
    std::stable_sort(paths.begin(), paths.end(), [](const std::string& a, const std::string& b) { return depth(a) < depth(b); });
    std::map<std::string, std::vector<const KeyRequest*>> by_path;
    for (const KeyRequest* r : requests) by_path[r->map_path].push_back(r);
    for (const std::string& raw : paths) {
      const std::string norm = normalise(raw);
      for (const KeyRequest* r : by_path[raw]) {
        keys_[norm].insert(r->key);
        if (!r->names.empty()) names_[norm] = r->names;
      }
    }
  }

  /// The normalised map path of a request's map.
  std::string map_path(const std::string& raw) { return normalise(raw); }

  /// The normalised key of a request (its map's names stand in for a name).
  static std::string key(const KeyRequest& r) { return r.names.empty() ? r.key : r.names; }

 private:
  static size_t depth(const std::string& path) {
    return path.empty() ? 0 : 1 + static_cast<size_t>(std::count(path.begin(), path.end(), '.'));
  }

  std::string normalise(const std::string& raw) {
    if (raw.empty()) return "";
    if (const auto it = done_.find(raw); it != done_.end()) return it->second;
    const auto [parent_raw, segment] = split_last(raw);
    const std::string parent = normalise(parent_raw);
    const std::string base = without_index(segment);
    std::string named;
    if (const auto it = names_.find(parent); it != names_.end()) named = it->second;
    else if (keys_[parent].count(base)) named = base;
    else named = "NAME";
    if (has_index(segment)) named += "[]";
    const std::string out = parent.empty() ? named : parent + "." + named;
    done_[raw] = out;
    return out;
  }

  std::map<std::string, std::set<std::string>> keys_;  ///< normalised map path -> keys asked for
  std::map<std::string, std::string> names_;           ///< normalised map path -> what its keys name
  std::map<std::string, std::string> done_;
};

bool is_contact_parameter(const KeyRequest& r) {
  if (r.kind != "number" || !r.names.empty()) return false;
  const ParamSpec* p = find_param(r.key);
  return p && r.min && r.max && *r.min == p->min_value && *r.max == p->max_value && r.unit == p->unit;
}

/// The rows of one kind of document, in the order the readers first asked for them.
std::vector<Row> rows_of(const std::vector<const KeyRequest*>& requests, const std::string& source_dir) {
  Normaliser names(requests);
  std::vector<Row> rows;
  std::map<std::string, size_t> index;
  for (const KeyRequest* r : requests) {
    const std::string map = names.map_path(r->map_path);
    const bool parameter = is_contact_parameter(*r);
    const std::string key = parameter ? "CONTACT_PARAMETER" : Normaliser::key(*r);
    const std::string path = map.empty() ? key : map + "." + key;
    auto [it, fresh] = index.try_emplace(path, rows.size());
    if (fresh) rows.emplace_back().key = path;
    Row& row = rows[it->second];
    row.contact_parameter = parameter;
    if (!parameter) {
      add_unique(row.kinds, r->kind);
      if (!r->shape.empty()) add_unique(row.shapes, r->shape);
      add_unique(row.fallbacks, shown_fallback(*r));
      add_unique(row.ranges, shown_range(*r));
      if (row.unit.empty()) row.unit = r->unit;
    }
    if (row.example.empty() && !r->value.empty()) {
      row.example = parameter ? r->key + ": " + r->value : r->value;
      row.example_file = fs::path(r->file).lexically_relative(source_dir).filename().string();
    }
  }
  return rows;
}

/// The section a case row belongs to: its top-level key, or equipment.GENERATOR.
std::string case_section(const std::string& key) {
  const size_t dot = key.find('.');
  if (dot == std::string::npos) return "";
  std::string first = without_index(key.substr(0, dot));
  if (first == "equipment") {
    const size_t next = key.find('.', dot + 1);
    if (next != std::string::npos) return key.substr(0, next);
  }
  return first;
}

std::vector<Section> case_sections(const std::vector<Row>& rows) {
  std::vector<Section> sections{{"", {}}};
  std::map<std::string, size_t> index{{"", 0}};
  // Sections in the order the case reader asks for the top-level keys, equipment generators
  // where `equipment` is.
  for (const Row& row : rows)
    if (row.key.find('.') == std::string::npos && !index.count(row.key)) {
      index[row.key] = sections.size();
      sections.push_back({row.key, {}});
    }
  for (const Row& row : rows) {
    const std::string name = case_section(row.key);
    if (!index.count(name)) {
      // equipment.GENERATOR: after `equipment` and the generators before it.
      size_t at = index.count("equipment") ? index["equipment"] + 1 : sections.size();
      while (at < sections.size() && sections[at].title.rfind("equipment.", 0) == 0) ++at;
      sections.insert(sections.begin() + static_cast<std::ptrdiff_t>(at), Section{name, {}});
      for (auto& [title, k] : index)
        if (k >= at) ++k;
      index[name] = at;
    }
    sections[index[name]].rows.push_back(row);
  }
  std::erase_if(sections, [](const Section& s) { return s.rows.empty(); });
  return sections;
}

std::string cell(const std::string& text, bool markdown) {
  if (!markdown) return text;
  std::string out;
  for (char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

std::string code(const std::string& text, bool markdown) {
  if (text.empty() || !markdown) return cell(text, markdown);
  return "`" + cell(text, markdown) + "`";
}

std::string shortened(const std::string& text) {
  if (text.size() <= 48) return text;
  return text.substr(0, 45) + "...";
}

std::string joined(const std::vector<std::string>& words, const std::string& between) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : between) + w;
  return out;
}

/// The printed cells of a row: key, type, unit, default, valid range, example.
std::vector<std::string> cells_of(const Row& row, bool markdown, bool& derived) {
  if (row.contact_parameter) {
    const std::string see = markdown ? "see [contact parameters](#contact-parameters)" : "see contact parameters";
    return {code(row.key, markdown), "number", "", see, "", row.example.empty() ? "" : code(shortened(row.example), markdown) + " (" + row.example_file + ")"};
  }
  std::vector<std::string> kinds;
  for (const std::string& k : row.kinds) {
    if (k == "section") {
      for (const std::string& s : row.shapes) add_unique(kinds, s);
      if (row.shapes.empty()) add_unique(kinds, "section");
    } else {
      add_unique(kinds, shown_kind(k));
    }
  }
  const bool varies = row.fallbacks.size() > 1 || row.ranges.size() > 1;
  derived = derived || varies;
  std::string fallback = row.fallbacks.empty() ? "" : row.fallbacks.front();
  std::string range = row.ranges.empty() ? "" : row.ranges.front();
  if (varies) fallback += fallback.empty() ? "*" : " *", range += range.empty() ? "" : " *";
  return {code(row.key, markdown), joined(kinds, " or "), cell(row.unit, markdown), cell(fallback, markdown), cell(range, markdown),
          row.example.empty() ? "" : code(shortened(row.example), markdown) + " (" + row.example_file + ")"};
}

void table(std::string& out, const std::vector<Row>& rows, bool markdown) {
  bool derived = false;
  std::vector<std::vector<std::string>> lines;
  for (const Row& row : rows) lines.push_back(cells_of(row, markdown, derived));
  const std::vector<std::string> head = {"key", "type", "unit", "default", "valid", "example (file)"};
  if (markdown) {
    out += "| " + joined(head, " | ") + " |\n|---|---|---|---|---|---|\n";
    for (const auto& line : lines) out += "| " + joined(line, " | ") + " |\n";
  } else {
    std::vector<size_t> width(head.size());
    for (size_t c = 0; c < head.size(); ++c) {
      width[c] = head[c].size();
      for (const auto& line : lines) width[c] = std::max(width[c], line[c].size());
    }
    const auto print = [&](const std::vector<std::string>& line) {
      std::string text = " ";
      for (size_t c = 0; c < line.size(); ++c) text += " " + line[c] + std::string(width[c] - line[c].size(), ' ');
      while (!text.empty() && text.back() == ' ') text.pop_back();
      out += text + "\n";
    };
    print(head);
    for (const auto& line : lines) print(line);
  }
  if (derived)
    out += markdown ? "\n\\* depends on other keys or on where the map is; shown: the value the readers met first.\n"
                    : "  * depends on other keys or on where the map is; shown: the value the readers met first.\n";
}

void heading(std::string& out, int level, const std::string& title, bool markdown) {
  if (markdown) out += fmt::format("\n{} {}\n\n", std::string(static_cast<size_t>(level), '#'), title);
  else out += fmt::format("\n{}\n", title);
}

std::string mixing_name(Mixing m) {
  switch (m) {
    case Mixing::arithmetic: return "arithmetic mean";
    case Mixing::geometric: return "geometric mean";
    case Mixing::harmonic: return "harmonic mean";
    case Mixing::minimum: return "smaller";
    case Mixing::maximum: return "larger";
  }
  return "";
}

/// The contact parameters and options, from the effect table (src/contact/effect_table.cpp).
void contact_tables(std::string& out, bool markdown) {
  heading(out, 2, "Contact parameters", markdown);
  out += "Keys of `materials.NAME`, `interactions[]`, a material file's `properties` and `walls.NAME`, and a "
         "measurement file's `particles` and `walls.NAME` (what was measured). A pair's value is mixed from its two "
         "materials' values unless `interactions` gives it; a material that does not state the key leaves the pair "
         "the other's value (a wall that says nothing of rolling resistance or cohesion takes the particles'), and the "
         "default applies only when neither states it. From the effect table; `demdesign effects` prints it with "
         "each effect's source.\n\n";
  if (markdown) out += "| key | effect | unit | default | valid | pair value | tunable |\n|---|---|---|---|---|---|---|\n";
  for (const EffectSpec* e : effect_table())
    for (const ParamSpec& p : e->params) {
      const std::string effect = fmt::format("contact.{}: {}", stage_name(e->stage), e->name);
      const std::string range = fmt::format("[{}, {}]", shown_number(p.min_value), shown_number(p.max_value));
      if (markdown)
        out += fmt::format("| `{}` | `{}` | {} | {} | {} | {} | {} |\n", p.key, effect, p.unit, shown_number(p.default_value), range,
                           mixing_name(p.mixing), p.tunable ? "yes" : "no");
      else
        out += fmt::format("  {:<28} {:<32} [{}] default {}, valid {}, pair: {}{}\n", p.key, effect, p.unit,
                           shown_number(p.default_value), range, mixing_name(p.mixing), p.tunable ? ", tunable" : "");
    }
  heading(out, 2, "Contact models and options", markdown);
  std::vector<std::string> additive;
  for (const Stage stage : kStages)
    if (stage_is_additive(stage)) additive.push_back(fmt::format("`{}`", stage_name(stage)));
  out += fmt::format("`contact.STAGE: MODEL` or `contact.STAGE: {{model: MODEL, OPTION: VALUE}}`; {} take a list of models.\n\n",
                     joined(additive, " and "));
  if (markdown) out += "| stage | model | option | values (first: default) |\n|---|---|---|---|\n";
  for (const EffectSpec* e : effect_table()) {
    const std::string stage(stage_name(e->stage));
    if (e->options.empty()) {
      if (markdown) out += fmt::format("| `{}` | `{}` | | |\n", stage, e->name);
      else out += fmt::format("  contact.{}: {}\n", stage, e->name);
    }
    for (const OptionSpec& o : e->options) {
      std::vector<std::string> values(o.values.begin(), o.values.end());
      if (markdown) out += fmt::format("| `{}` | `{}` | `{}` | {} |\n", stage, e->name, o.key, joined(values, ", "));
      else out += fmt::format("  contact.{}: {{model: {}, {}: {}}}\n", stage, e->name, o.key, joined(values, " | "));
    }
  }
}

}  // namespace

std::string default_source_dir() { return fs::path(materials::library_folder()).parent_path().string(); }

std::string case_key_reference(const std::string& source_dir, bool markdown) {
  const fs::path root = fs::absolute(source_dir).lexically_normal();
  const std::string defaults_file = "(defaults)";
  // The shipped cases, then a case that uses the sections none of them does.
  std::vector<fs::path> cases = yaml_files(root / "cases"), material_files = yaml_files(root / "materials"), measurement_files;
  cases.push_back(root / "tests" / "data" / "case_keys_coverage.yaml");
  for (const fs::path& folder : {root / "cases" / "calibration", root / "tests" / "data", root / "tests" / "data" / "cross_engine"})
    for (const fs::path& file : yaml_files(folder)) {
      const Document kind = kind_of(file);
      if (kind == Document::material_file) material_files.push_back(file);
      if (kind == Document::measurement_file) measurement_files.push_back(file);
    }

  Collector collector;
  // The generators with no parameters first: their defaults are the ones the table shows.
  for (const std::string& generator : equipment::generator_names()) {
    EquipmentSpec spec;
    spec.type = generator;
    spec.params = std::make_shared<const YAML::Node>(YAML::Node(YAML::NodeType::Map));
    spec.file = defaults_file;
    equipment::generate(spec);
  }
  for (const fs::path& file : cases) {
    CaseSpec spec = parse_case_file(file.string(), materials::library_lookup());
    equipment::expand_equipment(spec);
    read_sweep(read_yaml_file(file.string(), "the case file"), file.string());
  }
  for (const fs::path& file : material_files) materials::read_material_model(file.string());
  for (const fs::path& file : measurement_files) materials::read_measurements(file.string());

  // Which document each request read: material files wherever a case or a model read them.
  std::set<std::string> material_names, measurement_names;
  for (const fs::path& f : material_files) material_names.insert(f.string());
  for (const fs::path& f : measurement_files) measurement_names.insert(f.string());
  std::map<Document, std::vector<const KeyRequest*>> by_document;
  for (const KeyRequest& r : collector.requests) {
    const std::string file = r.file == defaults_file ? r.file : fs::path(r.file).lexically_normal().string();
    if (fs::path(file).filename() == "__material_model__.yaml") continue;  // read_material_model's own wrapper case
    const Document d = measurement_names.count(file) ? Document::measurement_file
                       : material_names.count(file)  ? Document::material_file
                                                     : Document::case_file;
    by_document[d].push_back(&r);
  }

  std::string out;
  if (markdown)
    out += "<!-- Generated by `demdesign keys --markdown > docs/case-keys.md` (app/cli/case_keys.cpp); do not edit by hand. -->\n"
           "# Case-key reference\n\n";
  else
    out += "Case-key reference (demdesign keys; Markdown: demdesign keys --markdown)\n\n";
  out += "Every key the readers of demdesign ask for, recorded while they read the shipped cases (cases/), material "
         "files (materials/) and measurement files (cases/calibration/, tests/data/cross_engine/), and each equipment "
         "generator with no parameters. Key paths: `[]` is any item of a list, NAME a name you choose (a material, a "
         "clump template, a wall material), MESH, PARAMETER, OBSERVABLE, SETUP_KEY and KEY_PATH what those keys name. "
         "Units are SI unless the unit column says otherwise; `valid` is the inclusive range or the allowed words; a "
         "section is a map or list holding the keys below it. Defaults shown are those with every other key at its "
         "default: some follow other keys (a screw's pitch its diameter; the layout rules are in each generator's "
         "file), and an asterisk marks those the shipped files show to vary. A key that is not listed is an error that names "
         "the nearest valid key. Sections no shipped case uses are read from tests/data/case_keys_coverage.yaml. How "
         "to write a case: docs/cases.md.\n";

  const std::vector<Row> case_rows = rows_of(by_document[Document::case_file], root.string());
  heading(out, 2, "Case files", markdown);
  for (const Section& section : case_sections(case_rows)) {
    heading(out, 3, section.title.empty() ? "Top level" : markdown ? "`" + section.title + "`" : section.title, markdown);
    table(out, section.rows, markdown);
  }
  heading(out, 2, "Material files", markdown);
  out += "`materials/NAME.yaml`, used in a case as `materials: {NAME: {library: FILE_STEM}}` and by the calibration "
         "commands (docs/materials-and-calibration.md).\n\n";
  table(out, rows_of(by_document[Document::material_file], root.string()), markdown);
  heading(out, 2, "Measurement files", markdown);
  out += "What was measured, for `demdesign compare`, `calibrate` and `diagnose` (docs/materials-and-calibration.md). "
         "The set-up keys and observables of each test are listed there.\n\n";
  table(out, rows_of(by_document[Document::measurement_file], root.string()), markdown);
  contact_tables(out, markdown);
  return out;
}

}  // namespace dem::app
