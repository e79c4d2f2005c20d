// BVH (Biovision Hierarchy) in and out: a liberal reader, the import into a Model and a Clip, and
// a conservative writer for any Model. docs: ../shared/reference/ecosystem.md §1.
//
//   io/bvh_document.hpp  the file in memory, its limits, channels and forward kinematics
//   io/bvh_parser.hpp    parse_bvh: what the reader accepts, tolerates and refuses
//   io/bvh_euler.hpp     rotation orders and Euler angles
//   io/bvh_import.hpp    import_bvh, load_bvh_file: units, masses, collision capsules
//   io/bvh_writer.hpp    make_bvh_document, format_bvh, write_bvh, save_bvh_file
#pragma once

#include "io/bvh_document.hpp"
#include "io/bvh_euler.hpp"
#include "io/bvh_import.hpp"
#include "io/bvh_parser.hpp"
#include "io/bvh_writer.hpp"
