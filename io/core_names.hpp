// The core types that io/ reads and writes, named inside namespace io without the core:: prefix.
#pragma once

#include "core/clip.hpp"
#include "core/model.hpp"
#include "core/model_builder.hpp"
#include "core/skin.hpp"
#include "core/spatial.hpp"

namespace io {

using core::Clip;
using core::Matrix3;
using core::Model;
using core::ModelBuilder;
using core::ModelError;
using core::Quaternion;
using core::SkinnedMesh;
using core::Transform;
using core::Vector3;

}  // namespace io
