// nvib: time integration of nonlinear vibration systems M a + F(u, v, t) = P(t).
#pragma once

#include "core/mass.hpp"
#include "core/model.hpp"
#include "core/newton.hpp"
#include "core/scheme.hpp"
#include "core/static_equilibrium.hpp"
#include "core/stepper.hpp"
#include "core/types.hpp"
#include "effects/effects.hpp"
#include "linalg/expm.hpp"
#include "schemes/all.hpp"
#include "solve.hpp"
