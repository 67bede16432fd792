#pragma once
// The two-level family, MLHCC (Xiang et al. §4.3, Alg. 3): a top-level cut of b/2 nodes, then the
// HCC cut of b/2 nodes under the first top node the ray segment overlaps (cl/keys_cut.h,
// rs_two_level_cut_code).
#include "bvh/cut.h"
#include "encode/cut_tables.h"
#include "encode/encode_scene.h"

namespace raysort {

// MLHCC for keys of `bits` bits: its cut and tables (two_level_tables) with rows of half boxes,
// cached.
struct TwoLevelInputs : TwoLevelTables {
  unsigned half = 0;
  TwoLevelCut cut;
};
const TwoLevelInputs& two_level_inputs(const EncodeScene& scene, unsigned bits);

}  // namespace raysort
