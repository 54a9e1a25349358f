#include "core/domain.h"

#include "core/forces.h"
#include "core/mesh_contacts.h"
#include "core/neighbors.h"

namespace dem {

WholeState ready_for_results(const Model& model, State gathered) {
  WholeState whole;
  whole.state = std::move(gathered);
  place_meshes(model, whole.state.time, whole.work);
  rebuild_contacts(model, whole.state, whole.work);
  whole.evaluated = whole.state;
  compute_forces(model, whole.evaluated, whole.work);  // advances the copy's histories only
  return whole;
}

}  // namespace dem
