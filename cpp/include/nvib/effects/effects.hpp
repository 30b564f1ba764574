// The built-in effects: laws on measures d = g . u, their sets and the models built from them.
#pragma once

#include "assembly.hpp"
#include "effect.hpp"
#include "effect_array.hpp"
#include "effect_set.hpp"
#include "laws.hpp"
#include "signal.hpp"
