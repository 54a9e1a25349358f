// When things first happen in a run, to the step: the first particle to reach each outlet, to
// cross each plane sensor, and to leave the domain. The run checks every few steps (with its
// numerical checks); a particle found past a boundary is traced back along its velocity to the
// step at which its centre crossed it, so that the time does not depend on how often rows of
// scalars are written.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/state.h"

namespace dem {

struct RunEvent {
  std::string what;           ///< "first at outlet bin", "first across sensor outlet_plane", "first out of the domain"
  double time = 0;            // [s] the step at which the centre crossed
  std::int64_t step = 0;
  std::int64_t particle = 0;  ///< the particle's id
};

/// Watches a run for its first events. Costs a pass over the particles per check while an event
/// is still to come, nothing after.
class EventWatch {
 public:
  explicit EventWatch(const Model& model);
  /// Events of an earlier part of the run (a resumed run keeps them).
  void restore(const std::vector<RunEvent>& earlier);
  /// Looks at the state; `since` [s] is the time of the previous check (crossings are not
  /// traced back before it). Returns true when an event fired.
  bool check(const Model& model, const State& state, double since);
  bool pending() const;
  const std::vector<RunEvent>& fired() const { return fired_; }

 private:
  struct Watch {
    enum class Kind { outlet, sensor, domain } kind;
    std::size_t index = 0;  ///< outlet or sensor
    std::string what;
    bool done = false;
  };
  std::vector<Watch> watches_;
  std::vector<RunEvent> fired_;
};

/// events.csv: what,time_s,step,particle_id, in the order the events happened.
std::string events_csv(const std::vector<RunEvent>& events);
/// The events of an earlier events.csv up to `time` (missing file: none).
std::vector<RunEvent> read_events(const std::string& path, double time);

}  // namespace dem
