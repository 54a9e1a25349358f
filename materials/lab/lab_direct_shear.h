// The periodic direct shear test (the source paper's Fig. 9): consolidation under a servo-
// controlled rough top plate, pre-shear, shear at a lower normal stress; stresses from the plate
// forces, checked against the contact stress tensor (Eq. 5). Called by run_virtual_test.
#pragma once

#include "lab/virtual_tests.h"

namespace dem::materials {

SimulatedOutcome run_direct_shear(const MaterialModel& model, const TestSetup& setup, const TestOptions& options);

}  // namespace dem::materials
