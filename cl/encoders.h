/* raysort — the encoder list: every encoder once, in id order, and every encoder family once. The
 * kernel ids (RS_ENC_*, keys.h), the host's enum class Encoder and encoder table
 * (host/encode/encoder.h), the encode kernels (cl/encode.cl) and the host twin's spatial dispatch
 * (keys_spatial.h, rs_spatial_code) are all made from these two lists, so nothing else has to be
 * kept in step by hand. docs/encoders.md, "Adding an encoder", says which files a new one touches.
 *
 * RS_ENCODERS(ENCODER, SPATIAL) calls, per encoder:
 *   ENCODER(ID, Host, "name", family, weight, ("alias", ...))   an encoder of a family's kernel
 *   SPATIAL(ID, Host, "name", code, weight, ("alias", ...))     a spatial encoder: a kernel of its own
 *     ID        its kernel id, RS_ENC_<ID> (the position in this list: NoSort is 0)
 *     Host      the host's Encoder::<Host>
 *     "name"    as the command line and result sets spell it
 *     family    its family: the kernels encode_<family>_k32 / _k64 (RS_DEFINE_<family>_KERNELS, in
 *               encode.cl or the family's kernel header) and the host's encoder_family_<family>()
 *               (host/encode/<family>_family.cpp)
 *     code      a spatial key rs_<code>_code(frame, ray) (keys_spatial.h), and its kernels
 *               encode_<code>_k32 / _k64 (Meister et al. 2020's encoders; Xiang et al. section 3.2)
 *     weight    encode + sort on top of a trace, in % (the shard planner's cost, bench/shard.h),
 *               measured on PoCL in the quick preset; the issue-21 rows are estimated from HCC's
 *     aliases   other spellings parse_encoder accepts, in parentheses, none or more: every row has
 *               six arguments, since OpenCL C 1.2 has no variadic macros (NVIDIA's compiler refuses
 *               them; clang accepts them as an extension, so nvptx-build.sh makes that an error)
 * RS_ENCODER_FAMILIES(FAMILY) calls FAMILY(family) once per family, spatial included.
 */
#ifndef RAYSORT_ENCODERS_H
#define RAYSORT_ENCODERS_H

#define RS_ENCODERS(ENCODER, SPATIAL)                                                  \
  ENCODER(NOSORT, NoSort, "nosort", nosort, 100, ("none", "nosorting"))                \
  SPATIAL(ORIGIN, Origin, "origin", origin, 115, ())                                   \
  SPATIAL(REIS, Reis, "reis", reis, 128, ())                                           \
  SPATIAL(COSTA, Costa, "costa", costa, 128, ())                                       \
  SPATIAL(AILA, Aila, "aila", aila, 125, ("aila_compact"))                             \
  SPATIAL(TWOPOINT, TwoPoint, "twopoint", twopoint, 122, ())                           \
  ENCODER(REGULAR_GRID, RegularGrid, "grid", box_set, 128, ("regular-grid"))           \
  ENCODER(HCC, HCC, "hcc", box_set, 128, ("hierarchy-cut", "hierarchy-cut-code"))      \
  ENCODER(MLHCC, MLHCC, "mlhcc", two_level, 142, ())                                   \
  ENCODER(PPC, PPC, "ppc", prefix_path, 165, ("prefix-path", "prefix-path-code"))      \
  ENCODER(HCC_DIR, HCC_DIR, "hcc-dir", box_set, 150, ())                               \
  ENCODER(HCC_REGION, HCC_REGION, "hcc-region", region_cut, 135, ("region"))           \
  ENCODER(HCC_TRAFFIC, HCC_TRAFFIC, "hcc-traffic", box_set, 135, ("traffic"))          \
  ENCODER(MLHCC_COST, MLHCC_COST, "mlhcc-cost", cost_cut, 150, ("cost"))

#define RS_ENCODER_FAMILIES(FAMILY) \
  FAMILY(nosort)                    \
  FAMILY(spatial)                   \
  FAMILY(box_set)                   \
  FAMILY(two_level)                 \
  FAMILY(prefix_path)               \
  FAMILY(region_cut)                \
  FAMILY(cost_cut)

/* A row macro that makes nothing of a row (for the lists' other kind of row). */
#define RS_NO_ROW(ID, HOST, NAME, FAMILY_OR_CODE, WEIGHT, ALIASES)

#endif /* RAYSORT_ENCODERS_H */
