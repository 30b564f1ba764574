// nvib: time integration of nonlinear vibration systems M a + F(u, v, t) = P(t).
//
// The layers, each in its folder, each including only those above it:
//   base/     the vocabulary: vectors, errors, counters, declared parameters, interrupts
//   linalg/   factorisations and the matrix exponential
//   model/    the mass and the model M a + K u + C v + f(u, v, t) = 0
//   effects/  the laws and the declared effects that make a model's f
//   newton/   the Newton component: its options, the iteration matrix, the linear system
//   schemes/  the scheme contract, the stepper, the registry of schemes
//   solve/    the one loop and its observers; the exact elastic spectrum (spectrum.hpp, base/ only)
#pragma once

#include "base/types.hpp"
#include "effects/effects.hpp"
#include "linalg/expm.hpp"
#include "model/mass.hpp"
#include "model/model.hpp"
#include "newton/newton.hpp"
#include "newton/static_equilibrium.hpp"
#include "schemes/all.hpp"
#include "schemes/scheme.hpp"
#include "schemes/stepper.hpp"
#include "solve/solve.hpp"
#include "solve/spectrum.hpp"
