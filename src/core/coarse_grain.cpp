// Coarse graining: the case's factor, parcels from real particle sets and inlets, the scaling of
// the pair parameters by each parameter's declared exponent, and what the run says about it. The
// law, its sources and the alternatives it rejects are in coarse_grain.h.
#include "core/coarse_grain.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string_view>
#include <utility>

namespace dem {

namespace {

/// A particle set or an inlet, for the messages: its key path, its factor and where it is.
struct Source {
  std::string key;  ///< "particles[0]", "inlets[1]"
  double coarse_grain;
  const SourceLocation* location;
};

/// Design values of the equipment (Model::design, named by the generators in equipment/) that are
/// the width of a passage the bulk flows through. Rejected: every value in metres, which would
/// warn about heights, spacings and a screw's clearance, which no particle is meant to pass.
constexpr std::string_view kOpeningDesignValues[] = {"orifice_diameter_m", "chute_width_m", "skirt_width_m",
                                                     "spoon_trough_width_m"};

/// "0.008 m", or "0.004-0.012 m" for a distribution.
std::string diameters_text(const SizeDistributionSpec& d) {
  if (d.kind == SizeDistributionSpec::Kind::fixed) return fmt::format("{:.4g} m", d.value);
  return fmt::format("{:.4g}-{:.4g} m", d.smallest(), d.largest());
}

/// [m] The largest parcel diameter (volume-equivalent for a clump) the model's sets and inlets draw.
double largest_parcel(const Model& model) {
  double largest = 0;
  for (const ParticleSource& s : model.sources) largest = std::max(largest, s.spec.diameter.largest());
  for (const Inlet& in : model.inlets) largest = std::max(largest, in.spec.diameter.largest());
  return largest;
}

/// One line per particle set and inlet: its parcels against the real particles they stand for.
std::vector<std::string> parcel_lines(const CaseSpec& spec, const Model& model) {
  const double f = model.coarse_grain;
  std::vector<std::string> lines;
  for (size_t k = 0; k < model.sources.size() && k < spec.particles.size(); ++k) {
    const ParticleSetSpec& real = spec.particles[k];
    const ParticleSetSpec& parcels = model.sources[k].spec;
    const std::string count = real.positions.empty()
                                  ? fmt::format("{} real particles as {} parcels", real.count, parcels.count)
                                  : fmt::format("{} parcels at the given positions (about {:.4g} real particles)", parcels.count,
                                                static_cast<double>(parcels.count) * f * f * f);
    lines.push_back(fmt::format("particles[{}] ({}): {}; parcel diameters {} (real {})", k, real.material, count,
                                diameters_text(parcels.diameter), diameters_text(real.diameter)));
  }
  for (size_t k = 0; k < model.inlets.size() && k < spec.inlets.size(); ++k) {
    const InletSpec& real = spec.inlets[k];
    const InletSpec& parcels = model.inlets[k].spec;
    std::string rate = real.mass_rate > 0
                           ? fmt::format("{:.4g} t/h, the real mass rate, in {:.4g} x fewer parcels", real.mass_rate * 3.6, f * f * f)
                           : std::string("fills its region");
    if (real.count > 0) rate += fmt::format(", stops after {} real particles ({} parcels)", real.count, parcels.count);
    lines.push_back(fmt::format("inlets.{} ({}): {}; parcel diameters {} (real {})", real.name, real.material, rate,
                                diameters_text(parcels.diameter), diameters_text(real.diameter)));
  }
  return lines;
}

/// The parameters the law changed (with their factor) and those it kept, over the active effects.
std::vector<std::string> parameter_lines(const Model& model) {
  std::string scaled, kept;
  for (const ActiveEffect& e : model.effects)
    for (const ParamSpec& p : e.spec->params) {
      const int exponent = p.coarse_grain_exponent.value_or(0);
      if (exponent == 0)
        kept += fmt::format("{}{}", kept.empty() ? "" : ", ", p.key);
      else
        scaled += fmt::format("{}{} [{}] x {:.4g} (F^{})", scaled.empty() ? "" : ", ", p.key, p.unit,
                              coarse_grain_factor(model.coarse_grain, exponent), exponent);
    }
  return {fmt::format("contact parameters scaled (stress similarity): {}", scaled.empty() ? "none in this contact law" : scaled),
          fmt::format("unchanged: density, Young's modulus, Poisson ratio (the Hertz law is self-similar){}{}",
                      kept.empty() ? "" : ", ", kept)};
}

}  // namespace

double case_coarse_grain(const CaseSpec& spec) {
  std::vector<Source> sources;
  for (size_t k = 0; k < spec.particles.size(); ++k)
    sources.push_back({fmt::format("particles[{}]", k), spec.particles[k].coarse_grain, &spec.particles[k].location});
  for (size_t k = 0; k < spec.inlets.size(); ++k)
    sources.push_back({fmt::format("inlets[{}]", k), spec.inlets[k].coarse_grain, &spec.inlets[k].location});
  for (const Source& s : sources)
    if (!(std::isfinite(s.coarse_grain) && s.coarse_grain >= 1.0 && s.coarse_grain <= kMostCoarseGrain))
      throw CaseError(fmt::format("{}: {}.coarse_grain: {:g} is out of range; valid: [1, {:g}] (1: real particles)", s.location->str(),
                                  s.key, s.coarse_grain, kMostCoarseGrain));
  if (sources.empty()) return 1.0;
  const Source& first = sources.front();
  for (const Source& s : sources)
    if (s.coarse_grain != first.coarse_grain)
      throw CaseError(fmt::format(
          "{}: {}.coarse_grain: {:g} differs from {}.coarse_grain {:g} ({}); mixed coarse graining is out of scope: every inlet and "
          "particle set of a case must give the same coarse_grain (or none), since a contact between parcels of two factors has no "
          "stress-similar pair law",
          s.location->str(), s.key, s.coarse_grain, first.key, first.coarse_grain, first.location->str()));
  return first.coarse_grain;
}

double coarse_grain_factor(double coarse_grain, int exponent) { return std::pow(coarse_grain, exponent); }

SizeDistributionSpec parcel_diameters(const SizeDistributionSpec& real, double coarse_grain) {
  SizeDistributionSpec d = real;
  d.value *= coarse_grain;
  d.mean *= coarse_grain;
  d.std_dev *= coarse_grain;
  d.min *= coarse_grain;
  d.max *= coarse_grain;
  for (double& v : d.values) v *= coarse_grain;
  return d;
}

std::int64_t parcel_count(std::int64_t real_count, double coarse_grain) {
  const double parcels = static_cast<double>(real_count) / (coarse_grain * coarse_grain * coarse_grain);
  return std::max<std::int64_t>(1, std::llround(parcels));
}

void make_parcels(ParticleSetSpec& set, double coarse_grain) {
  set.diameter = parcel_diameters(set.diameter, coarse_grain);
  if (set.positions.empty()) set.count = parcel_count(set.count, coarse_grain);
}

void make_parcels(InletSpec& inlet, double coarse_grain) {
  inlet.diameter = parcel_diameters(inlet.diameter, coarse_grain);
  if (inlet.count > 0) inlet.count = parcel_count(inlet.count, coarse_grain);
}

void scale_pair_parameters(Model& model) {
  const size_t rows = static_cast<size_t>(model.n_materials()) * static_cast<size_t>(model.n_materials());
  for (const ActiveEffect& e : model.effects)
    for (size_t k = 0; k < e.spec->params.size(); ++k) {
      const ParamSpec& p = e.spec->params[k];
      if (!p.coarse_grain_exponent)
        throw CaseError(fmt::format(
            "{}: coarse_grain: the {} effect '{}' does not say how its parameter '{}' [{}] scales with the parcel size "
            "(ParamSpec::coarse_grain_exponent); coarse graining does not guess: run real particles (no coarse_grain), or declare "
            "the exponent in the effect's parameter table",
            model.source, stage_name(e.spec->stage), e.spec->name, p.key, p.unit));
      if (*p.coarse_grain_exponent == 0) continue;
      const double factor = coarse_grain_factor(model.coarse_grain, *p.coarse_grain_exponent);
      for (size_t t = 0; t < rows; ++t) model.pair_table[t * static_cast<size_t>(model.pair_stride) + e.param_offset + k] *= factor;
    }
}

std::vector<std::string> narrow_openings(const Model& model) {
  const double parcel = largest_parcel(model);  // [m]
  std::vector<std::string> warnings;
  if (!(parcel > 0)) return warnings;
  const auto check = [&](const std::string& what, double width) {
    if (!(width < kOpeningParcelDiameters * parcel)) return;
    warnings.push_back(fmt::format(
        "{} is {:.3g} m across, {:.2g} parcel diameters of {:.3g} m (F = {:g}; {:.3g} real diameters): below about {:g} an opening "
        "arches and jams where the real material flows. Lower coarse_grain, or do not take the flow through it as the real one",
        what, width, width / parcel, parcel, model.coarse_grain, width * model.coarse_grain / parcel, kOpeningParcelDiameters));
  };
  for (const PlaneWall& w : model.planes) {
    if (w.shape == PlaneWall::Shape::disc && w.hole > 0) check(fmt::format("the hole of wall '{}' (an orifice)", w.name), 2.0 * w.hole);
    if (w.round()) check(fmt::format("wall '{}' (a {})", w.name, w.shape == PlaneWall::Shape::tube ? "tube" : "cylinder"), 2.0 * w.radius);
  }
  for (const auto& [name, value] : model.design)
    for (const std::string_view opening : kOpeningDesignValues)
      if (name == opening) check(fmt::format("the equipment's {}", name), value);
  return warnings;
}

std::vector<std::string> calibration_coarse_grain_notes(const CaseSpec& spec, double coarse_grain) {
  std::vector<std::string> notes;
  for (const MaterialSpec& m : spec.materials) {
    if (!m.calibration) continue;
    const auto made_of = [&](const auto& sources) {
      return std::any_of(sources.begin(), sources.end(), [&](const auto& s) { return s.material == m.name; });
    };
    if (!made_of(spec.particles) && !made_of(spec.inlets)) continue;  // a wall material's calibration has no parcels
    const double calibrated = m.calibration->coarse_grain;
    if (std::abs(calibrated - coarse_grain) <= 1e-9 * coarse_grain) continue;
    notes.push_back(fmt::format(
        "{} ({}) was calibrated at coarse_grain {:g} and is used here at coarse_grain {:g}: the scaling law carries it (stress "
        "similarity, core/coarse_grain.h), but the fit was made at the other parcel size; compare at {:g} to check "
        "(demdesign compare {} {} --coarse-grain {:g}), or add `coarse_grain_check:` to see what the parcel size moves",
        m.name, m.library_file, calibrated, coarse_grain, coarse_grain, m.library_file,
        m.calibration->measurements.empty() ? std::string("MEASUREMENTS") : m.calibration->measurements, coarse_grain));
  }
  return notes;
}

std::vector<std::string> describe_coarse_grain(const CaseSpec& spec, const Model& model) {
  const double f = model.coarse_grain;
  if (f == 1.0) return {};
  std::vector<std::string> lines = {fmt::format(
      "COARSE GRAINING: F = {:g}: each particle is a parcel standing for {:.4g} real particles of the same material, {:g} x their "
      "diameter (stress similarity: Bierwisch et al. 2009; Radl et al. 2011; Chu et al. 2016)",
      f, f * f * f, f)};
  for (std::string& line : parcel_lines(spec, model)) lines.push_back(std::move(line));
  for (std::string& line : parameter_lines(model)) lines.push_back(std::move(line));
  lines.push_back(fmt::format("what it saves: {:.4g} x fewer particles and a time step about {:g} x as long (contact and Rayleigh times "
                              "grow with the diameter): about {:.4g} x less computing than the real particles",
                              f * f * f, f, f * f * f * f));
  lines.push_back(
      "results are the real material's, not rescaled: mass flow, drive power, wall pressure and wear (bulk stresses, velocities "
      "and energy density are kept by the law; Archard sliding work per area and Bitter impact energy per area and time are "
      "both linear in the bulk's energy flux onto a wall)");
  lines.push_back(fmt::format(
      "not reproduced: effects of the size distribution at its real scale (segregation, fines percolation, dust); openings "
      "must stay {:g} parcel diameters wide or more",
      kOpeningParcelDiameters));
  for (const std::string& warning : narrow_openings(model)) lines.push_back("WARNING: " + warning);
  return lines;
}

}  // namespace dem
