// Linked cells with a Verlet skin. The contact lists are rebuilt only when some particle has
// used up its share of the skin since the last rebuild (half of it, measured from where the
// spheres' common drift has carried its build position where walls are static: DriftLimits,
// verlet.h); at each rebuild particles leaving the domain are removed, the particle slots are
// sorted by cell (neighbours near in memory), and every contact's history is carried to its new
// slot by particle id.
#pragma once

#include <cmath>

#include "core/model.h"
#include "core/state.h"
#include "core/workspace.h"

namespace dem {

/// True when the lists no longer cover every contact that could form, the spheres being where
/// they are at `time` [s]. With free_spheres_checked the caller has already tested the free
/// spheres (step's fused kick and drift) and only spheres of bodies, glued spheres and meshes
/// are tested here.
bool needs_rebuild(const Model& model, const State& state, const Workspace& work, double time, bool free_spheres_checked = false);

/// Whether the lists follow the spheres' common drift (DriftLimits, verlet.h): no plane or mesh
/// moves (a static wall only needs each sphere within a skin of where it was listed), no sphere
/// is glued to a wall, no ranks (each would drift its own way).
bool lists_follow_drift(const Model& model, const Workspace& work);
/// Rebuilds the contact lists (see above).
void rebuild_contacts(const Model& model, State& state, Workspace& work);
/// Rebuilds the workspace's indexing of the state's contact lists without changing them (after
/// a restart, so the run continues exactly as it would have).
void index_contacts(const Model& model, const State& state, Workspace& work);
/// Replaces d by its minimum image along the periodic axes. Inline, with the rounding only for
/// the few pairs that reach across half a period (the same result bit for bit as rounding every
/// pair: nearbyint of |d/L| <= 1/2 is zero): as a call to libm's nearbyint per listed pair it
/// took a visible share of a periodic drum's time (bench/results/design_measurements.csv).
inline void minimum_image(const Model& model, double d[3]) {
  for (int a = 0; a < 3; ++a) {
    const double period = model.period[a];
    if (period > 0 && std::abs(d[a]) > 0.5 * period) d[a] -= period * std::nearbyint(d[a] / period);
  }
}

}  // namespace dem
