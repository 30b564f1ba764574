// The built-in effects: laws on measures d = g . u, their sets and the models built from them.
#pragma once

#include "assembly.hpp"
#include "effect.hpp"
#include "effect_set.hpp"
#include "kernels.hpp"
#include "law.hpp"
#include "laws/all.hpp"
#include "signal.hpp"
#include "user_law.hpp"
