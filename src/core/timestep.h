// Time-step advisor: the Rayleigh wave time of the smallest particle and the shortest binary
// contact time set how large a step can be.
#pragma once

#include "core/model.h"

namespace dem {

/// Rayleigh time T_R = pi R sqrt(rho/G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu))
/// (Li, Xu & Thornton 2005 approximation of the Rayleigh root) [s].
double rayleigh_time(double radius, double density, double youngs, double poisson);

// hertz_contact_time(): contact/effect.h, beside the normal laws that give their contact times.

/// The step to use and whether it is safe. Unsafe: above 40 % of the Rayleigh time, or fewer
/// than kMinStepsPerContact steps in the shortest contact. Automatic: `rayleigh_fraction` of the
/// Rayleigh time, and at least `steps_per_contact` (default 20) steps per contact.
TimeStepAdvice advise_time_step(const Model& model, const SimulationSpec& sim);

}  // namespace dem
