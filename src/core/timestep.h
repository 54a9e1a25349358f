// Time-step advisor: the Rayleigh wave time of the smallest particle and the shortest binary
// contact time set how large a step can be.
#pragma once

#include "core/model.h"

namespace dem {

/// Rayleigh time T_R = pi R sqrt(rho/G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu))
/// (Li, Xu & Thornton 2005 approximation of the Rayleigh root) [s].
double rayleigh_time(double radius, double density, double youngs, double poisson);

/// Hertz contact duration 2.8683 (m*^2 / (R* E*^2 v))^(1/5) [s] (Johnson 1985, validation CL-1).
double hertz_contact_time(double m_eff, double r_eff, double youngs_eff, double speed);

/// The step to use and whether it is safe. Unsafe: above 40 % of the Rayleigh time, or fewer
/// than kMinStepsPerContact steps in the shortest contact. Automatic: `rayleigh_fraction` of the
/// Rayleigh time, and at least `steps_per_contact` (default 20) steps per contact.
TimeStepAdvice advise_time_step(const Model& model, const SimulationSpec& sim);

}  // namespace dem
