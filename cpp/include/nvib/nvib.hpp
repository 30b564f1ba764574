// nvib: time integration of nonlinear vibration systems M a + F(u, v, t) = P(t).
#pragma once

#include "core/mass.hpp"
#include "core/model.hpp"
#include "core/newton.hpp"
#include "core/stepper.hpp"
#include "core/types.hpp"
#include "effects/effects.hpp"
#include "linalg/expm.hpp"
#include "schemes/cemdts.hpp"
#include "schemes/central_difference.hpp"
#include "schemes/generalized_alpha.hpp"
#include "schemes/newmark.hpp"
#include "schemes/precise_integration.hpp"
#include "schemes/zhai.hpp"
#include "solve.hpp"
