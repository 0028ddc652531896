// slslam._core: the compiled half of slslam. One bind_<module>.cpp per C++ module.
#include <exception>
#include <stdexcept>

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
void BindMapIo(py::module_& m);
#ifdef SLSLAM_WITH_PCL
void BindLidar(py::module_& m);
#endif
}  // namespace slslam::bindings

PYBIND11_MODULE(_core, m) {
  m.doc() = "slslam C++ core (camera geometry, rectification, features)";
  m.attr("__version__") = SLSLAM_VERSION;
  m.attr("__git_commit__") = SLSLAM_GIT_COMMIT;
  // A failed check (std::invalid_argument: an option's Check(), a Require on an input) reaches
  // Python as slslam.errors.InputError, the project's error type (a ValueError): one line that
  // names the option or input, which the command line prints without a traceback.
  static py::handle input_error =
      py::object(py::module_::import("slslam.errors").attr("InputError")).release();
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const std::invalid_argument& e) {
      PyErr_SetObject(input_error.ptr(), py::make_tuple(py::none(), e.what()).ptr());
    }
  });
  slslam::bindings::BindCore(m);
  slslam::bindings::BindFeatures(m);
  slslam::bindings::BindSim(m);
  slslam::bindings::BindRayCaster(m);
  slslam::bindings::BindLines(m);
  slslam::bindings::BindTracking(m);
  slslam::bindings::BindPlace(m);
  slslam::bindings::BindMapIo(m);
#ifdef SLSLAM_WITH_PCL
  slslam::bindings::BindLidar(m);
#endif
}
