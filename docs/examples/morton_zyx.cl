/* An encoder from a file (docs/encoders.md, "An encoder from a file"): the Morton code of the ray's
 * origin with the axes in z, y, x order per level, where the built-in Origin encoder interleaves
 * x, y, z. Run it with
 *
 *   raysort run --scenes cornell --encoders origin,file:docs/examples/morton_zyx.cl
 *   raysort encodebench --scene cornell --encoders origin,file:docs/examples/morton_zyx.cl
 *
 * raysort compiles this file inside cl/encode_file.h, which gives it the suite's key helpers
 * (cl/keys.h: rs_quantize_point, rs_morton3, RS_ORIGIN_LEVELS) and calls rs_file_code once per ray.
 * The key of `bits` bits is the code's top bits; `scene` (HCC's cut, the BVH) is not needed here.
 */
rs_u64 rs_file_code(const RsEncodeFrame* frame, RsRay ray, uint bits, const RsFileScene* scene) {
  rs_u32 q[3]; /* the origin's cell in the scene box, 22 bits per axis */
  rs_quantize_point(frame, rs_load3(ray.o), RS_ORIGIN_LEVELS, q);
  /* Levels 0..20 of z, y, x (63 bits), then z of level 21: Origin's code with x and z swapped. */
  return (rs_morton3(q[2] >> 1, q[1] >> 1, q[0] >> 1) << 1) | (q[2] & 1u);
}
