// Bindings for map files: what `slslam info` shows about a saved atlas without loading it.
// (Saving and loading go through the tracker, which holds the maps.)
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "slslam/map/map_io.h"

namespace py = pybind11;

namespace slslam::bindings {

void BindMapIo(py::module_& m) {
  m.def(
      "read_map_file_header",
      [](const std::string& path) {
        MapFileSummary s;
        {
          py::gil_scoped_release release;
          s = ReadMapFileSummary(path);
        }
        const MapFileHeader& h = s.header;
        py::object descriptor_type = py::none();
        if (h.descriptor_type == CV_8U) descriptor_type = py::str("binary");
        if (h.descriptor_type == CV_32F) descriptor_type = py::str("float");
        py::list maps;
        for (const MapFileSummary::Counts& c : s.maps) {
          maps.append(py::dict(py::arg("keyframes") = c.keyframes,
                               py::arg("culled_keyframes") = c.retired,
                               py::arg("points") = c.points, py::arg("lines") = c.lines));
        }
        const PinholeCamera& camera = h.rig.camera;
        return py::dict(
            py::arg("format_version") = s.format_version,
            py::arg("slslam_version") = h.slslam_version,
            py::arg("descriptor_type") = descriptor_type,
            py::arg("descriptor_cols") = h.descriptor_cols, py::arg("vocabulary") = h.vocabulary,
            py::arg("line_descriptor") = LineDescriptorName(h.line_descriptor),
            py::arg("camera") =
                py::dict(py::arg("fx") = camera.fx, py::arg("fy") = camera.fy,
                         py::arg("cx") = camera.cx, py::arg("cy") = camera.cy,
                         py::arg("width") = camera.width, py::arg("height") = camera.height),
            py::arg("baseline_m") = h.rig.baseline_m,
            py::arg("next_ids") = py::dict(py::arg("keyframe") = s.next_ids.next_keyframe,
                                           py::arg("point") = s.next_ids.next_point,
                                           py::arg("line") = s.next_ids.next_line),
            py::arg("maps") = maps);
      },
      py::arg("path"),
      "Header of a map file (.slmap) as a dict: format_version, slslam_version, descriptor_type "
      "('binary', 'float' or None), descriptor_cols, vocabulary, line_descriptor ('opencv_lbd' or "
      "'lbd'; format 1 files: 'opencv_lbd'), camera {fx, fy, cx, cy, width, "
      "height} [px], baseline_m, next_ids {keyframe, point, line}, and per map {keyframes, "
      "culled_keyframes, points, lines}. Checks magic, version, size and checksum (the whole file "
      "is read) but builds no map; a foreign, damaged or newer file raises ValueError naming it.");
}

}  // namespace slslam::bindings
