// The exact elastic spectrum (nvib/solve/spectrum.hpp): every period and damping of one record in
// one call, with the GIL released while it runs.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "bind_types.hpp"

namespace nvib_py {

using nvib::Vector;

// The oscillators (period, damping) of a call, flat, and the shape its results take: (periods,) for one
// damping or one per period, (dampings, periods) for a list of dampings.
struct SpectrumGrid {
  Vector periods, damping;
  py::tuple shape;
};

inline SpectrumGrid spectrum_grid(const Vector& periods, const py::object& damping, bool per_period) {
  SpectrumGrid g;
  const auto m = periods.size();
  if (py::isinstance<py::float_>(damping) || py::isinstance<py::int_>(damping)) {
    if (per_period) raise_value_error("damping", "per_period=True needs one damping per period, got one value");
    g.periods = periods;
    g.damping = Vector::Constant(m, damping.cast<double>());
    g.shape = py::make_tuple(m);
    return g;
  }
  Vector z;
  try {
    z = damping.cast<Vector>();
  } catch (const py::cast_error&) {
    raise_type_error("damping", "expected a number or a 1-D sequence of numbers");
  }
  if (per_period) {
    if (z.size() != m)
      raise_value_error("damping", "per_period=True needs one damping per period (" + std::to_string(m) + "), got " +
                                       std::to_string(z.size()));
    g.periods = periods;
    g.damping = z;
    g.shape = py::make_tuple(m);
    return g;
  }
  if (z.size() == 0) raise_value_error("damping", "expected at least one damping ratio");
  g.periods.resize(m * z.size());
  g.damping.resize(m * z.size());
  for (Eigen::Index k = 0; k < z.size(); ++k) {
    g.periods.segment(k * m, m) = periods;
    g.damping.segment(k * m, m).setConstant(z[k]);
  }
  g.shape = py::make_tuple(z.size(), m);
  return g;
}

inline py::dict spectrum_dict(const nvib::ElasticSpectrum& s, const py::tuple& shape) {
  py::dict d;
  auto put = [&](const char* name, const Vector& x) { d[name] = py::cast(x).attr("reshape")(shape); };
  put("periods", s.periods);
  put("damping", s.damping);
  put("Sd", s.Sd);
  put("Sv", s.Sv);
  put("PSv", s.PSv);
  put("PSa", s.PSa);
  put("Sa", s.Sa);
  put("t_Sd", s.t_Sd);
  put("t_Sv", s.t_Sv);
  put("t_Sa", s.t_Sa);
  return d;
}

inline void bind_spectrum(py::module_& m) {
  m.def(
      "elastic_spectrum",
      [](const Vector& ag, double dt, const Vector& periods, const py::object& damping, bool per_period,
         bool free_vibration, double t0) {
        const SpectrumGrid g = spectrum_grid(periods, damping, per_period);
        nvib::ElasticSpectrumOptions opt;
        opt.free_vibration = free_vibration;
        nvib::ElasticSpectrum s;
        {
          py::gil_scoped_release nogil;
          s = nvib::elastic_spectrum(ag, dt, g.periods, g.damping, opt, t0);
        }
        return spectrum_dict(s, g.shape);
      },
      py::arg("ag"), py::arg("dt"), py::arg("periods"), py::arg("damping") = 0.05, py::kw_only(),
      py::arg("per_period") = false, py::arg("free_vibration") = true, py::arg("t0") = 0.0,
      "The exact elastic spectrum of the record ag (samples dt apart, linear between them) at every period:\n"
      "a dict of arrays Sd, Sv (relative velocity), PSv, PSa, Sa (absolute acceleration) and the peaks' times\n"
      "t_Sd, t_Sv, t_Sa. damping: one value (arrays of the periods' shape), a list (arrays (dampings, periods)),\n"
      "or one per period with per_period=True. free_vibration: include the free vibration after the record.");
  m.def(
      "elastic_spectrum_at",
      [](const Vector& times, const Vector& ag, const Vector& periods, const py::object& damping, bool per_period,
         bool free_vibration) {
        const SpectrumGrid g = spectrum_grid(periods, damping, per_period);
        nvib::ElasticSpectrumOptions opt;
        opt.free_vibration = free_vibration;
        nvib::ElasticSpectrum s;
        {
          py::gil_scoped_release nogil;
          s = nvib::elastic_spectrum_at(times, ag, g.periods, g.damping, opt);
        }
        return spectrum_dict(s, g.shape);
      },
      py::arg("times"), py::arg("ag"), py::arg("periods"), py::arg("damping") = 0.05, py::kw_only(),
      py::arg("per_period") = false, py::arg("free_vibration") = true,
      "elastic_spectrum for samples at increasing times (any spacing).");
  m.def(
      "rotated_sd",
      [](const Vector& a1, const Vector& a2, double dt, const Vector& periods, const py::object& damping,
         const Vector& angles) {
        Vector z;
        if (py::isinstance<py::float_>(damping) || py::isinstance<py::int_>(damping))
          z = Vector::Constant(1, damping.cast<double>());
        else
          z = damping.cast<Vector>();
        py::gil_scoped_release nogil;
        return nvib::rotated_sd(a1, a2, dt, periods, z, angles);
      },
      py::arg("a1"), py::arg("a2"), py::arg("dt"), py::arg("periods"), py::arg("damping"), py::arg("angles"),
      "Sd (angles x periods) of the oscillators under a1 cos(theta) + a2 sin(theta) at each angle [degrees],\n"
      "exactly; damping: one value or one per period.");
}

}  // namespace nvib_py
