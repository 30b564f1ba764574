// The registry of laws: every law header and the list of them. A law's runtime tag is its place in
// the list; the binding, the scene parser and the tests read the list. A new law is one header,
// its name here and its tests.
#pragma once

#include "../law.hpp"
#include "bilinear.hpp"
#include "bouc_wen.hpp"
#include "compiled.hpp"
#include "constant_force.hpp"
#include "cubic_spring.hpp"
#include "damper.hpp"
#include "friction.hpp"
#include "gap.hpp"
#include "ground_acceleration.hpp"
#include "hardening_spring.hpp"
#include "harmonic_force.hpp"
#include "hertz_contact.hpp"
#include "hook.hpp"
#include "imk_peak_oriented.hpp"
#include "p_delta.hpp"
#include "pendulum_gravity.hpp"
#include "power_damper.hpp"
#include "spring.hpp"

namespace nvib {
namespace effects {

// The order is the evaluation order of the effects' groups (and so of the sums of their forces).
using AllLaws = LawList<Spring, Damper, HardeningSpring, CubicSpring, PowerDamper, PendulumGravity, HertzContact,
                        ConstantForce, HarmonicForce, GroundAcceleration, Bilinear, BoucWen, Friction, Gap, Hook,
                        ImkPeakOriented, PDelta, Compiled, CompiledState>;

}  // namespace effects
}  // namespace nvib
