// slslam._core: the compiled half of slslam. One bind_<module>.cpp per C++ module.
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace slslam::bindings {
void BindCore(py::module_& m);
void BindFeatures(py::module_& m);
void BindSim(py::module_& m);
void BindRayCaster(py::module_& m);
void BindLines(py::module_& m);
void BindTracking(py::module_& m);
void BindPlace(py::module_& m);
#ifdef SLSLAM_WITH_PCL
void BindLidar(py::module_& m);
#endif
}  // namespace slslam::bindings

PYBIND11_MODULE(_core, m) {
  m.doc() = "slslam C++ core (camera geometry, rectification, features)";
  m.attr("__version__") = SLSLAM_VERSION;
  slslam::bindings::BindCore(m);
  slslam::bindings::BindFeatures(m);
  slslam::bindings::BindSim(m);
  slslam::bindings::BindRayCaster(m);
  slslam::bindings::BindLines(m);
  slslam::bindings::BindTracking(m);
  slslam::bindings::BindPlace(m);
#ifdef SLSLAM_WITH_PCL
  slslam::bindings::BindLidar(m);
#endif
}
