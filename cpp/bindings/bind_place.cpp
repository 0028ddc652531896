// Bindings for place recognition: the BoW vocabulary and the keyframe database.
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "bindings/image_conversion.h"
#include "slslam/place/keyframe_database.h"
#include "slslam/place/vocabulary.h"

namespace py = pybind11;

namespace slslam::bindings {
namespace {

const char* KindName(int type) { return type == CV_8U ? "binary" : "float"; }

}  // namespace

void BindPlace(py::module_& m) {
  py::class_<VocabularyOptions>(m, "VocabularyOptions", "Hierarchical k-means options.")
      .def(py::init<>())
      .def_readwrite("branching", &VocabularyOptions::branching, "k of the k-means tree [-]")
      .def_readwrite("levels", &VocabularyOptions::levels, "depth L of the tree [-]")
      .def_readwrite("kmeans_iterations", &VocabularyOptions::kmeans_iterations,
                     "Lloyd iterations per node [-]")
      .def_readwrite("seed", &VocabularyOptions::seed, "k-means++ seed [-]")
      .def("check", &VocabularyOptions::Check);

  py::class_<Vocabulary>(m, "Vocabulary",
                         "Bag-of-words vocabulary (hierarchical k-means, TF-IDF, L1 score).")
      .def(py::init<>())
      .def_static(
          "train",
          [](const std::vector<py::array>& descriptors_per_image,
             const VocabularyOptions& options) {
            // Headers over the arrays, which the caller's list keeps alive during the call.
            std::vector<cv::Mat> mats;
            mats.reserve(descriptors_per_image.size());
            for (const py::array& array : descriptors_per_image) {
              mats.push_back(WrapDescriptors(array));
            }
            py::gil_scoped_release release;
            return Vocabulary::Train(mats, options);
          },
          py::arg("descriptors_per_image"), py::arg("options") = VocabularyOptions{},
          "Train on one (N, D) array per image: all uint8 (binary, D bytes) or all float32.")
      .def_static("load", &Vocabulary::Load, py::arg("path"),
                  py::call_guard<py::gil_scoped_release>(),
                  "Read a .slvoc file; ValueError naming the path when it is not a valid one.")
      .def("save", &Vocabulary::Save, py::arg("path"), py::call_guard<py::gil_scoped_release>(),
           "Write a .slvoc file (through path + '.partial' and a rename).")
      .def_property_readonly("empty", &Vocabulary::empty)
      .def_property_readonly("num_words", &Vocabulary::num_words)
      .def_property_readonly("num_nodes", &Vocabulary::num_nodes)
      .def_property_readonly("branching", &Vocabulary::branching)
      .def_property_readonly("levels", &Vocabulary::levels)
      .def_property_readonly(
          "descriptor_type",
          [](const Vocabulary& v) -> py::object {
            if (v.empty()) return py::none();
            return py::str(KindName(v.descriptor_type()));
          },
          "'binary' (uint8, Hamming) or 'float' (float32, L2); None when empty.")
      .def_property_readonly("descriptor_cols", &Vocabulary::descriptor_cols,
                             "bytes (binary) or floats per descriptor")
      .def("word_weight", &Vocabulary::word_weight, py::arg("word"), "IDF weight of a word.")
      .def(
          "transform",
          [](const Vocabulary& v, const py::array& descriptors) {
            const cv::Mat mat = WrapDescriptors(descriptors);
            BowVector bow;
            {
              py::gil_scoped_release release;
              v.Transform(mat, &bow);
            }
            return bow;
          },
          py::arg("descriptors"), "BoW vector {word: weight} (TF-IDF, L1-normalised).")
      .def(
          "transform_with_features",
          [](const Vocabulary& v, const py::array& descriptors, int levels_up) {
            const cv::Mat mat = WrapDescriptors(descriptors);
            BowVector bow;
            FeatureVector features;
            {
              py::gil_scoped_release release;
              v.Transform(mat, &bow, &features, levels_up);
            }
            return py::make_tuple(bow, features);
          },
          py::arg("descriptors"), py::arg("levels_up") = 2,
          "(BoW vector, {node: [feature rows]}) with nodes levels_up above the leaves.")
      .def_static("score", &Vocabulary::Score, py::arg("a"), py::arg("b"),
                  "L1 score 1 - 0.5 |a - b|_1 of two BoW vectors, in [0, 1].");

  using Candidate = KeyframeDatabase::Candidate;
  py::class_<Candidate>(m, "PlaceCandidate", "A keyframe returned by KeyframeDatabase.query.")
      .def_readonly("keyframe_id", &Candidate::keyframe_id)
      .def_readonly("score", &Candidate::score)
      .def_readonly("shared_words", &Candidate::shared_words)
      .def("__repr__", [](const Candidate& c) {
        return "PlaceCandidate(keyframe_id=" + std::to_string(c.keyframe_id) +
               ", score=" + std::to_string(c.score) +
               ", shared_words=" + std::to_string(c.shared_words) + ")";
      });

  py::class_<KeyframeDatabase>(m, "KeyframeDatabase",
                               "Inverted index of keyframe BoW vectors (thread-safe).")
      .def(py::init<>())
      .def("add", &KeyframeDatabase::Add, py::arg("keyframe_id"), py::arg("bow"))
      .def("remove", &KeyframeDatabase::Remove, py::arg("keyframe_id"))
      .def("clear", &KeyframeDatabase::Clear)
      .def("__len__", &KeyframeDatabase::size)
      .def("__contains__", &KeyframeDatabase::Contains)
      .def(
          "query",
          [](const KeyframeDatabase& db, const BowVector& bow, int max_results, double min_score,
             double min_shared_ratio, const std::function<bool(int)>& accept) {
            if (accept) return db.Query(bow, max_results, min_score, min_shared_ratio, accept);
            py::gil_scoped_release release;
            return db.Query(bow, max_results, min_score, min_shared_ratio);
          },
          py::arg("bow"), py::arg("max_results") = 10, py::arg("min_score") = 0.0,
          py::arg("min_shared_ratio") = 0.8, py::arg("accept") = nullptr,
          "Keyframes sharing words with bow, best score first; accept(id) -> bool filters ids.");
}

}  // namespace slslam::bindings
