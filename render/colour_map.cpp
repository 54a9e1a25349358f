// Colour maps as short tables of (t, r, g, b), linearly interpolated.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/render.h"

namespace dem::render {

namespace {

struct Stop {
  float t, r, g, b;
};

struct Table {
  const char* name;
  std::span<const Stop> stops;
};

// viridis (van der Walt and Smith, 2015; CC0): matplotlib's 256-entry table at every 32nd entry.
// Nine stops stay within 0.01 of the full table, far below what a print or screen shows.
constexpr Stop viridis[] = {
    {0 / 255.f, 0.267004f, 0.004874f, 0.329415f},   {32 / 255.f, 0.278826f, 0.175490f, 0.483397f},
    {64 / 255.f, 0.229739f, 0.322361f, 0.545706f},  {96 / 255.f, 0.172719f, 0.448791f, 0.557885f},
    {128 / 255.f, 0.127568f, 0.566949f, 0.550556f}, {160 / 255.f, 0.157851f, 0.683765f, 0.501686f},
    {192 / 255.f, 0.369214f, 0.788888f, 0.382914f}, {224 / 255.f, 0.678489f, 0.863742f, 0.189503f},
    {255 / 255.f, 0.993248f, 0.906157f, 0.143936f}};
// Diverging blue-grey-red (Moreland, "Diverging color maps for scientific visualization", 2009),
// for signed fields such as a velocity component.
constexpr Stop coolwarm[] = {{0.00f, 0.2298f, 0.2987f, 0.7537f},
                             {0.25f, 0.5543f, 0.6900f, 0.9955f},
                             {0.50f, 0.8650f, 0.8650f, 0.8650f},
                             {0.75f, 0.9605f, 0.6161f, 0.4812f},
                             {1.00f, 0.7057f, 0.0156f, 0.1502f}};
// Blue-cyan-green-yellow-red, the look of most commercial DEM post-processors.
constexpr Stop rainbow[] = {{0.00f, 0.0f, 0.0f, 1.0f},
                            {0.25f, 0.0f, 1.0f, 1.0f},
                            {0.50f, 0.0f, 1.0f, 0.0f},
                            {0.75f, 1.0f, 1.0f, 0.0f},
                            {1.00f, 1.0f, 0.0f, 0.0f}};
constexpr Stop grey[] = {{0.0f, 0.15f, 0.15f, 0.15f}, {1.0f, 0.90f, 0.90f, 0.90f}};

constexpr Table tables[] = {
    {"viridis", viridis}, {"coolwarm", coolwarm}, {"rainbow", rainbow}, {"grey", grey}};

const Table& find(const std::string& name) {
  for (const Table& table : tables)
    if (name == table.name) return table;
  std::string known;
  for (const Table& table : tables) known += std::string(known.empty() ? "" : ", ") + table.name;
  throw std::invalid_argument("render: unknown colour map '" + name + "' (known: " + known + ")");
}

}  // namespace

std::array<float, 3> colour_at(const std::string& name, double t) {
  const auto stops = find(name).stops;
  if (!(t > 0)) t = 0;  // NaN too: callers that want grey for NaN test before calling
  if (t >= 1) return {stops.back().r, stops.back().g, stops.back().b};
  std::size_t i = 1;
  while (i + 1 < stops.size() && stops[i].t < t) ++i;
  const Stop& a = stops[i - 1];
  const Stop& b = stops[i];
  const float w = std::clamp(float((t - a.t) / (b.t - a.t)), 0.0f, 1.0f);
  return {a.r + w * (b.r - a.r), a.g + w * (b.g - a.g), a.b + w * (b.b - a.b)};
}

std::vector<std::string> colour_map_names() {
  std::vector<std::string> names;
  for (const Table& table : tables) names.emplace_back(table.name);
  return names;
}

}  // namespace dem::render
