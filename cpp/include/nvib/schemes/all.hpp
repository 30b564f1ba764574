// The scheme registry: every scheme header, and the one list the binding, the
// command line, the labels and the tests are generated from. A new scheme is
// one header, its name in this list and one test file.
#pragma once

#include "cemdts.hpp"
#include "central_difference.hpp"
#include "generalized_alpha.hpp"
#include "newmark.hpp"
#include "precise_integration.hpp"
#include "scheme.hpp"
#include "zhai.hpp"

namespace nvib {

using AllSchemes = SchemeList<CentralDifference, CEMDTS, Zhai, Newmark, GeneralizedAlpha, PreciseIntegration>;

}  // namespace nvib
