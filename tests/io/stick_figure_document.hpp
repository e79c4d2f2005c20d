// Our own stick-figure glTF export, parsed by the tests' independent reader (tests/io/
// gltf_reader.hpp) into a document a test can edit and write out again: test files built on a
// real export rather than by hand.
#pragma once

#include <string>
#include <vector>

#include "core/clip.hpp"
#include "core/model.hpp"
#include "io/gltf.hpp"
#include "tests/io/gltf_reader.hpp"

namespace gltf_test {

/// The glTF of `model` playing `clip`, with a stick figure as its skinned mesh (every link a
/// bone), parsed; what the reader finds wrong is added to `errors`.
inline Document stick_figure_document(const core::Model& model,
                                      const core::Clip& clip,
                                      std::vector<std::string>& errors) {
  io::GltfExportOptions stick;
  stick.stick_figure = true;
  return parse_gltf(io::write_gltf(model, &clip, nullptr, stick), errors);
}

}  // namespace gltf_test
