// nvib._core: the pybind11 binding. Type erasure happens here only: a
// stepper is a template on (scheme, model); Python sees one Stepper type,
// one Model type and one class per scheme of the registry (schemes/all.hpp).
#include "bind_models.hpp"
#include "bind_result.hpp"
#include "bind_run.hpp"
#include "bind_schemes.hpp"
#include "bind_spectrum.hpp"
#include "bind_types.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "nvib C++ core (header-only library bound with pybind11)";
  nvib_py::bind_types(m);
  nvib_py::bind_schemes(m);
  nvib_py::bind_models(m);
  nvib_py::bind_result(m);
  nvib_py::bind_run(m);
  nvib_py::bind_spectrum(m);
}
