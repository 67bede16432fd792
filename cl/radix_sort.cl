/* raysort — LSD radix sort of (key, value) pairs: keys uint (32-bit) or ulong (64-bit), values uint.
 *
 * Method: least-significant-digit radix sort by "reduce-then-scan" counting sort passes
 * (Satish, Harris & Garland 2009, "Designing efficient sorting algorithms for manycore GPUs";
 * Merrill & Grimshaw 2011), in the chunked form that is also the classic CPU LSD radix sort:
 * every work-group owns one contiguous tile of the input, so a pass is
 *   1. rs_count    per-tile counts of the pass's digit, stored digit-major: counts[digit][tile];
 *   2. rs_scan     one exclusive scan over that digit-major array, which turns every count into
 *                  the output position of the tile's first key with that digit;
 *   3. rs_scatter  every tile writes its keys, in input order, from those positions on.
 * A tile's keys keep their input order and tiles are ranked in order, so every pass is stable,
 * which is what makes LSD correct. The first read of a sort (rs_count_bounds) also takes the OR
 * and the AND of all keys; the host reads those two words back once (rs_reduce_bounds) and skips
 * every pass whose digit is the same for all keys: OR and AND agree on a digit's bits exactly
 * when one bin of that digit's histogram holds every key. That costs two bit operations per key
 * instead of a histogram per pass, and the first read's counts serve the first pass if it runs.
 *
 * Inside a work-group (RS_WG work-items, each owning `items` consecutive keys of the tile):
 *   RS_WG == 1 (CPUs through PoCL): a work-item is a plain scalar loop, local memory is ordinary
 *     memory. The tile is one chunk scattered serially in order: no ranking, no barriers, the
 *     256 output streams of an 8-bit digit stay in cache.
 *   RS_WG  > 1 (GPUs): the tile is staged in local memory with coalesced reads; each work-item
 *     counts its own keys into its column of a [digit][work-item] table; one work-group scan of
 *     that table ranks every key stably inside the tile; keys are reordered by digit in local
 *     memory and written out in digit runs, so consecutive work-items write consecutive words.
 *
 * On NVIDIA the GPU shape's passes are Onesweep's instead (rs_hist_all, rs_hist_scan, rs_onesweep,
 * below): the same tiles, one kernel per pass, each tile's offsets found by a decoupled look-back.
 *
 * The host (host/sort/radix_sort.cpp) picks RS_RADIX_BITS, RS_WG and the tile size from the
 * device's type, local memory and maximum work-group size. OpenCL C 1.2, no sub-groups, every
 * barrier in uniform control flow, global sizes padded to a multiple of the local size
 * (docs/design.md, "Device facts").
 *
 * Build options (all required): RS_KEY_BITS (32 or 64), RS_RADIX_BITS, RS_WG, RS_MAX_ITEMS
 * (keys per work-item staged in local memory when RS_WG > 1), RS_SCAN_WG.
 */

#if RS_KEY_BITS == 64
typedef ulong rs_key;
#else
typedef uint rs_key;
#endif

#define RS_RADIX (1u << RS_RADIX_BITS)

/* The digit of pass p covers key bits [shift, shift + width) with width = RS_RADIX_BITS except
 * in the last pass, which stops at hi_bit (a 10-bit top-k sort by 8-bit digits: 8 + 2 bits). */
static inline uint rs_mask(uint shift, uint hi_bit) {
  uint width = min((uint)RS_RADIX_BITS, hi_bit - shift);
  return (1u << width) - 1u;
}
static inline uint rs_digit(rs_key key, uint shift, uint mask) { return (uint)(key >> shift) & mask; }

/* Per-tile counts of one digit, bits [shift, shift + width): counts[digit * tiles + tile]. A tile
 * is items * RS_WG keys. With bounds != 0 (the first read of a sort) the kernel also writes the
 * OR and the AND of the tile's keys to bounds[2 * tile], bounds[2 * tile + 1]. */
static inline void rs_count_tile(__global const rs_key* restrict keys, uint n, uint items, uint shift, uint hi_bit,
                          __global uint* restrict counts, __global rs_key* restrict bounds, const bool with_bounds,
                          __local uint* hist, __local rs_key* red_any, __local rs_key* red_all) {
  const uint lid = get_local_id(0);
  const uint tile = get_group_id(0);
  const uint tiles = get_num_groups(0);
  const uint mask = rs_mask(shift, hi_bit);
  for (uint d = lid; d < RS_RADIX; d += RS_WG) hist[d] = 0;
  barrier(CLK_LOCAL_MEM_FENCE);

  const uint begin = tile * items * RS_WG;
  const uint end = min(n, begin + items * RS_WG);
  rs_key any = 0, all = ~(rs_key)0;
  /* Strided: coalesced on a GPU, a sequential loop when RS_WG == 1. Order does not matter here. */
  for (uint i = begin + lid; i < end; i += RS_WG) {
    rs_key key = keys[i];
    if (with_bounds) {
      any |= key;
      all &= key;
    }
#if RS_WG == 1
    hist[rs_digit(key, shift, mask)] += 1u;
#else
    atomic_inc(&hist[rs_digit(key, shift, mask)]);
#endif
  }
  if (with_bounds) {
#if RS_WG == 1
    bounds[2 * tile] = any;
    bounds[2 * tile + 1] = all;
#else
    /* Tree reduction over the work-group (RS_WG is a power of two). */
    red_any[lid] = any;
    red_all[lid] = all;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint stride = RS_WG / 2; stride > 0; stride >>= 1) {
      if (lid < stride) {
        red_any[lid] |= red_any[lid + stride];
        red_all[lid] &= red_all[lid + stride];
      }
      barrier(CLK_LOCAL_MEM_FENCE);
    }
    if (lid == 0) {
      bounds[2 * tile] = red_any[0];
      bounds[2 * tile + 1] = red_all[0];
    }
#endif
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint d = lid; d < RS_RADIX; d += RS_WG) counts[d * tiles + tile] = hist[d];
}

__kernel void rs_count(__global const rs_key* restrict keys, uint n, uint items, uint shift, uint hi_bit,
                       __global uint* restrict counts) {
  __local uint hist[RS_RADIX];
  rs_count_tile(keys, n, items, shift, hi_bit, counts, 0, false, hist, 0, 0);
}

/* The first read of a sort: the first digit's tile counts and every tile's key OR and AND. */
__kernel void rs_count_bounds(__global const rs_key* restrict keys, uint n, uint items, uint shift, uint hi_bit,
                              __global uint* restrict counts, __global rs_key* restrict bounds) {
  __local uint hist[RS_RADIX];
  __local rs_key red_any[RS_WG], red_all[RS_WG]; /* OpenCL C 1.2: __local only at kernel scope */
  rs_count_tile(keys, n, items, shift, hi_bit, counts, bounds, true, hist, red_any, red_all);
}

/* OR and AND of all keys from the tiles' (one work-group). A digit is the same for every key
 * exactly when OR and AND agree on its bits, i.e. when one bin of its histogram holds all keys. */
__kernel void rs_reduce_bounds(__global const rs_key* restrict bounds, uint tiles, __global rs_key* restrict out) {
  __local rs_key red_any[RS_SCAN_WG], red_all[RS_SCAN_WG];
  const uint lid = get_local_id(0);
  rs_key any = 0, all = ~(rs_key)0;
  for (uint t = lid; t < tiles; t += RS_SCAN_WG) {
    any |= bounds[2 * t];
    all &= bounds[2 * t + 1];
  }
  red_any[lid] = any;
  red_all[lid] = all;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint stride = RS_SCAN_WG / 2; stride > 0; stride >>= 1) {
    if (lid < stride) {
      red_any[lid] |= red_any[lid + stride];
      red_all[lid] &= red_all[lid + stride];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) {
    out[0] = red_any[0];
    out[1] = red_all[0];
  }
}

/* Exclusive scan, in place, of counts[0 .. m): one work-group of RS_SCAN_WG work-items, each
 * owning a contiguous segment. Digit-major order makes the result the output position of every
 * (digit, tile) run. */
__kernel void rs_scan(__global uint* restrict counts, uint m) {
  __local uint partial[RS_SCAN_WG];
  const uint lid = get_local_id(0);
  const uint segment = (m + RS_SCAN_WG - 1) / RS_SCAN_WG;
  const uint begin = min(m, lid * segment);
  const uint end = min(m, (lid + 1) * segment);
  uint sum = 0;
  for (uint i = begin; i < end; ++i) sum += counts[i];
  partial[lid] = sum;
  barrier(CLK_LOCAL_MEM_FENCE);
  /* Hillis-Steele inclusive scan of the segment sums (log2 RS_SCAN_WG steps). */
  for (uint step = 1; step < RS_SCAN_WG; step <<= 1) {
    uint add = lid >= step ? partial[lid - step] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    partial[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  uint running = partial[lid] - sum;
  for (uint i = begin; i < end; ++i) {
    uint c = counts[i];
    counts[i] = running;
    running += c;
  }
}

#if RS_WG > 1
/* The local-memory tile of the GPU shape (RS_WG > 1), shared by rs_scatter and rs_onesweep. */
typedef struct {
  uint tile_n;                  /* keys in the tile */
  uint mine;                    /* this work-item's first key in the tile */
  rs_key keys[RS_MAX_ITEMS];    /* its `items` consecutive keys and values, in registers */
  uint values[RS_MAX_ITEMS];
} RsTileItems;

/* Steps 1-3 of a pass over the tile that starts at key tile_begin: staged (coalesced), counted per
 * work-item into rank[digit][work-item], and ranked stably by one exclusive scan of that table in
 * digit-major order. Afterwards rank[d * RS_WG] is the tile position of digit d's first key. */
static inline void rs_rank_tile(__global const rs_key* restrict keys_in, __global const uint* restrict values_in,
                                uint n, uint items, uint tile_begin, uint shift, uint mask,
                                __local rs_key* tile_keys, __local uint* tile_values, __local uint* rank,
                                __local uint* partial, RsTileItems* it) {
  const uint lid = get_local_id(0);
  it->tile_n = min(n - min(n, tile_begin), items * RS_WG);
  const uint tile_n = it->tile_n;

  /* 1. Stage the tile (coalesced) and clear this work-item's column. */
  for (uint i = lid; i < tile_n; i += RS_WG) {
    tile_keys[i] = keys_in[tile_begin + i];
    tile_values[i] = values_in[tile_begin + i];
  }
  for (uint d = 0; d < RS_RADIX; ++d) rank[d * RS_WG + lid] = 0;
  barrier(CLK_LOCAL_MEM_FENCE);

  /* 2. Each work-item counts its own `items` consecutive keys; keep them in registers. */
  it->mine = lid * items;
  for (uint j = 0; j < RS_MAX_ITEMS; ++j) {
    if (j < items && it->mine + j < tile_n) {
      it->keys[j] = tile_keys[it->mine + j];
      it->values[j] = tile_values[it->mine + j];
      rank[rs_digit(it->keys[j], shift, mask) * RS_WG + lid] += 1u;
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  /* 3. Exclusive scan of rank[] in digit-major order: work-item w owns entries
   *    [w * RS_RADIX, (w + 1) * RS_RADIX), a Hillis-Steele scan joins the segments. */
  uint sum = 0;
  for (uint e = 0; e < RS_RADIX; ++e) sum += rank[lid * RS_RADIX + e];
  partial[lid] = sum;
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint step = 1; step < RS_WG; step <<= 1) {
    uint add = lid >= step ? partial[lid - step] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    partial[lid] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  uint running = partial[lid] - sum;
  for (uint e = 0; e < RS_RADIX; ++e) {
    uint c = rank[lid * RS_RADIX + e];
    rank[lid * RS_RADIX + e] = running;
    running += c;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
}

/* Steps 4-5, once run_delta[d] (global position - tile position of digit d's run) is set and a
 * barrier has passed: the tile reordered by digit in local memory (stable: work-items in order,
 * keys in order), then written out so that consecutive work-items write consecutive positions
 * inside each digit's run. */
static inline void rs_write_tile(__global rs_key* restrict keys_out, __global uint* restrict values_out, uint items,
                                 uint shift, uint mask, __local rs_key* tile_keys, __local uint* tile_values,
                                 __local uint* rank, __local const uint* run_delta, const RsTileItems* it) {
  const uint lid = get_local_id(0);
  for (uint j = 0; j < RS_MAX_ITEMS; ++j) {
    if (j < items && it->mine + j < it->tile_n) {
      uint to = rank[rs_digit(it->keys[j], shift, mask) * RS_WG + lid]++;
      tile_keys[to] = it->keys[j];
      tile_values[to] = it->values[j];
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint i = lid; i < it->tile_n; i += RS_WG) {
    rs_key key = tile_keys[i];
    uint to = run_delta[rs_digit(key, shift, mask)] + i;
    keys_out[to] = key;
    values_out[to] = tile_values[i];
  }
}
#endif

/* One counting-sort pass: tile `tile` writes its keys, stably, from offsets[digit * tiles + tile]. */
__kernel void rs_scatter(__global const rs_key* restrict keys_in, __global const uint* restrict values_in,
                         __global rs_key* restrict keys_out, __global uint* restrict values_out, uint n, uint items,
                         uint shift, uint hi_bit, __global const uint* restrict offsets) {
  const uint tile = get_group_id(0);
  const uint tiles = get_num_groups(0);
  const uint mask = rs_mask(shift, hi_bit);
#if RS_WG == 1
  /* One work-item per tile: the tile's counts are this work-item's counts; scatter in order. */
  __local uint position[RS_RADIX];
  for (uint d = 0; d < RS_RADIX; ++d) position[d] = offsets[d * tiles + tile];
  const uint begin = tile * items;
  const uint end = min(n, begin + items);
  for (uint i = begin; i < end; ++i) {
    rs_key key = keys_in[i];
    uint to = position[rs_digit(key, shift, mask)]++;
    keys_out[to] = key;
    values_out[to] = values_in[i];
  }
#else
  __local rs_key tile_keys[RS_WG * RS_MAX_ITEMS];
  __local uint tile_values[RS_WG * RS_MAX_ITEMS];
  __local uint rank[RS_RADIX * RS_WG]; /* [digit][work-item]: counts, then ranks inside the tile */
  __local uint partial[RS_WG];
  __local uint run_delta[RS_RADIX]; /* global position - tile position of each digit's run */
  const uint lid = get_local_id(0);
  RsTileItems it;
  rs_rank_tile(keys_in, values_in, n, items, tile * items * RS_WG, shift, mask, tile_keys, tile_values, rank, partial,
               &it);
  for (uint d = lid; d < RS_RADIX; d += RS_WG) run_delta[d] = offsets[d * tiles + tile] - rank[d * RS_WG];
  barrier(CLK_LOCAL_MEM_FENCE); /* column 0 of rank[] is read above and advanced below */
  rs_write_tile(keys_out, values_out, items, shift, mask, tile_keys, tile_values, rank, run_delta, &it);
#endif
}

/* Passes of a key width: ceil(RS_KEY_BITS / RS_RADIX_BITS). */
#define RS_MAX_PASSES ((RS_KEY_BITS + RS_RADIX_BITS - 1) / RS_RADIX_BITS)

#if RS_WG > 1
/* ---------------------------------------------------------------------------------------------
 * Onesweep (Adinets & Merrill 2022, "Onesweep: A Faster Least Significant Digit Radix Sort for
 * GPUs"): one read of the keys takes the histograms of every pass (rs_hist_all, rs_hist_scan),
 * then each pass is ONE kernel (rs_onesweep) instead of count + scan + scatter: a tile ranks its
 * keys as rs_scatter does, and learns how many keys of each digit the tiles before it hold by a
 * decoupled look-back over their published counts. A tile takes its index from an atomic counter
 * in the order tiles start, so it only ever waits for tiles that have started; it still needs the
 * device to let a started work-group finish while another spins (forward progress between
 * work-groups), which OpenCL 1.2 does not promise: the host selects it by device (NVIDIA), and
 * the tests run it on PoCL and Oclgrind, whose work-groups run to completion.
 *
 * The sweep buffer (uint): [RS_MAX_PASSES][RS_RADIX] the global digit counts (zeroed before a
 * sort), scanned in place into each digit's first output position; then the tile counter and the
 * [tile][RS_RADIX] status table of the pass, zeroed before each pass. A status word is
 * a flag in its two top bits (0: nothing yet, AGGREGATE: the tile's own count of that digit,
 * INCLUSIVE: the count of that digit over this tile and every tile before it) and a 30-bit
 * count, written and read as one word with atomics, so no fence orders a count and its flag
 * (the host uses Onesweep below 2^30 pairs only).
 * ------------------------------------------------------------------------------------------- */
#define RS_SWEEP_AGGREGATE 0x40000000u
#define RS_SWEEP_INCLUSIVE 0x80000000u
#define RS_SWEEP_COUNT 0x3fffffffu

/* Zeroes sweep[first .. end) (a kernel, not clEnqueueFillBuffer: Oclgrind 21.10's
 * uninitialised-value check does not see what a fill writes). */
__kernel void rs_sweep_clear(__global uint* restrict sweep, uint first, uint end) {
  for (uint i = first + get_global_id(0); i < end; i += get_global_size(0)) sweep[i] = 0;
}

/* Digit counts of every pass in pass_mask (bit p: digit bits [lo + p * RS_RADIX_BITS, ...)) over
 * one tile, added into sweep[p * RS_RADIX + digit]. */
__kernel void rs_hist_all(__global const rs_key* restrict keys, uint n, uint items, uint lo, uint hi_bit,
                          uint pass_mask, __global uint* restrict sweep) {
  __local uint hist[RS_MAX_PASSES * RS_RADIX];
  const uint lid = get_local_id(0);
  for (uint i = lid; i < RS_MAX_PASSES * RS_RADIX; i += RS_WG) hist[i] = 0;
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint begin = get_group_id(0) * items * RS_WG;
  const uint end = min(n, begin + items * RS_WG);
  for (uint i = begin + lid; i < end; i += RS_WG) {
    const rs_key key = keys[i];
    for (uint p = 0; p < RS_MAX_PASSES; ++p) {
      if (!((pass_mask >> p) & 1u)) continue;
      const uint shift = lo + p * RS_RADIX_BITS;
      atomic_inc(&hist[p * RS_RADIX + rs_digit(key, shift, rs_mask(shift, hi_bit))]);
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  for (uint i = lid; i < RS_MAX_PASSES * RS_RADIX; i += RS_WG)
    if (hist[i]) atomic_add(&sweep[i], hist[i]);
}

/* Each pass's digit counts, scanned in place (exclusive): digit d's first output position. */
__kernel void rs_hist_scan(__global uint* restrict sweep) {
  for (uint p = get_local_id(0); p < RS_MAX_PASSES; p += RS_SCAN_WG) {
    uint running = 0;
    for (uint d = 0; d < RS_RADIX; ++d) {
      const uint c = sweep[p * RS_RADIX + d];
      sweep[p * RS_RADIX + d] = running;
      running += c;
    }
  }
}

/* One pass, whole: sweep[digits + d] is digit d's first output position, sweep[counter] the tile
 * counter and sweep[status ...] the status table of this pass (all zero but the positions). */
__kernel void rs_onesweep(__global const rs_key* restrict keys_in, __global const uint* restrict values_in,
                          __global rs_key* restrict keys_out, __global uint* restrict values_out, uint n, uint items,
                          uint shift, uint hi_bit, __global volatile uint* sweep, uint digits, uint counter,
                          uint status) {
  __local rs_key tile_keys[RS_WG * RS_MAX_ITEMS];
  __local uint tile_values[RS_WG * RS_MAX_ITEMS];
  __local uint rank[RS_RADIX * RS_WG];
  __local uint partial[RS_WG];
  __local uint run_delta[RS_RADIX];
  __local uint count[RS_RADIX];
  __local uint tile_index;
  const uint lid = get_local_id(0);
  const uint mask = rs_mask(shift, hi_bit);
  /* The tile in the order work-groups start, not get_group_id: a tile waits only for started ones. */
  if (lid == 0) tile_index = atomic_inc(&sweep[counter]);
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint tile = tile_index;
  RsTileItems it;
  rs_rank_tile(keys_in, values_in, n, items, tile * items * RS_WG, shift, mask, tile_keys, tile_values, rank, partial,
               &it);
  __global volatile uint* own = sweep + status + tile * RS_RADIX;
  /* Publish this tile's count of every digit first (the first tile's is already inclusive) ... */
  for (uint d = lid; d < RS_RADIX; d += RS_WG) {
    const uint end = d + 1 < RS_RADIX ? rank[(d + 1) * RS_WG] : it.tile_n;
    count[d] = end - rank[d * RS_WG];
    atomic_xchg(&own[d], (tile == 0 ? RS_SWEEP_INCLUSIVE : RS_SWEEP_AGGREGATE) | count[d]);
  }
  /* (every digit's, before any work-item waits: PoCL runs a work-group's work-items one after the
   * other between barriers, and a later tile may be waiting on any of these digits) */
  barrier(CLK_LOCAL_MEM_FENCE);
  /* ... then look back, digit by digit, over the tiles before it until one is inclusive. */
  for (uint d = lid; d < RS_RADIX; d += RS_WG) {
    uint before = 0;
    for (uint t = tile; t > 0;) {
      --t;
      uint word;
      do {
        word = atomic_or(&sweep[status + t * RS_RADIX + d], 0u);
      } while (!(word & (RS_SWEEP_AGGREGATE | RS_SWEEP_INCLUSIVE)));
      before += word & RS_SWEEP_COUNT;
      if (word & RS_SWEEP_INCLUSIVE) break;
    }
    if (tile > 0) atomic_xchg(&own[d], RS_SWEEP_INCLUSIVE | (before + count[d]));
    run_delta[d] = sweep[digits + d] + before - rank[d * RS_WG];
  }
  barrier(CLK_LOCAL_MEM_FENCE); /* column 0 of rank[] is read above and advanced below */
  rs_write_tile(keys_out, values_out, items, shift, mask, tile_keys, tile_values, rank, run_delta, &it);
}
#endif

#if RS_WG == 1
/* MSD-first hybrid, CPU shape only (the host uses it for large N, see radix_sort.cpp). After one
 * global stable counting pass on the most significant digit that varies (rs_count, rs_scan,
 * rs_scatter into keys_a/values_a), every bucket of that digit is a contiguous range that only
 * needs ordering by the lower digits. One work-group (one work-item) per bucket sorts its range
 * by those digits with LSD passes while it sits in cache: one read takes the histograms of all
 * of its passes (a histogram does not depend on the order of the keys), then every pass scatters
 * the range stably from one buffer into the same range of the other (a -> b -> a ...). Bucket d
 * is [offsets[d * tiles], offsets[(d + 1) * tiles]) of the scanned digit-major counts, the last
 * one ends at n. pass_mask: bit p set for each lower pass p (digit bits [lo + p * RS_RADIX_BITS,
 * ...)) that runs. With an odd number of passes the result is in keys_b/values_b, else in a. */
/* One stable pass of a bucket, src -> dst, from the positions in `position`. */
static inline void rs_bucket_pass(__global const rs_key* restrict src_k, __global const uint* restrict src_v,
                           __global rs_key* restrict dst_k, __global uint* restrict dst_v, uint begin, uint end,
                           uint shift, uint mask, __local uint* restrict position) {
  for (uint i = begin; i < end; ++i) {
    const rs_key key = src_k[i];
    const uint to = position[rs_digit(key, shift, mask)]++;
    dst_k[to] = key;
    dst_v[to] = src_v[i];
  }
}

/* Histograms of passes [j0, j1) over [begin, end) of keys, turned into their start positions. */
static inline void rs_bucket_hist(__global const rs_key* restrict keys, uint begin, uint end, uint j0, uint j1,
                           const uint* shifts, const uint* masks, __local uint* restrict hist) {
  for (uint j = j0 * RS_RADIX; j < j1 * RS_RADIX; ++j) hist[j] = 0;
  for (uint i = begin; i < end; ++i) {
    const rs_key key = keys[i];
    for (uint j = j0; j < j1; ++j) hist[j * RS_RADIX + rs_digit(key, shifts[j], masks[j])] += 1u;
  }
  for (uint j = j0; j < j1; ++j) {
    uint running = begin;
    for (uint e = 0; e < RS_RADIX; ++e) {
      const uint c = hist[j * RS_RADIX + e];
      hist[j * RS_RADIX + e] = running;
      running += c;
    }
  }
}

/* Passes [j0, j1) of [begin, end), LSD order; pass j reads a when j is even, b when odd. */
static inline void rs_bucket_lsd(__global rs_key* keys_a, __global uint* values_a, __global rs_key* keys_b,
                          __global uint* values_b, uint begin, uint end, uint j0, uint j1, const uint* shifts,
                          const uint* masks, __local uint* hist) {
  rs_bucket_hist((j0 & 1u) ? keys_b : keys_a, begin, end, j0, j1, shifts, masks, hist);
  for (uint j = j0; j < j1; ++j) {
    if (j & 1u)
      rs_bucket_pass(keys_b, values_b, keys_a, values_a, begin, end, shifts[j], masks[j], hist + j * RS_RADIX);
    else
      rs_bucket_pass(keys_a, values_a, keys_b, values_b, begin, end, shifts[j], masks[j], hist + j * RS_RADIX);
  }
}

__kernel void rs_bucket_sort(__global rs_key* keys_a, __global uint* values_a, __global rs_key* keys_b,
                             __global uint* values_b, uint n, uint tiles, __global const uint* restrict offsets,
                             uint lo, uint hi_bit, uint pass_mask) {
  __local uint hist[RS_MAX_PASSES * RS_RADIX];
  const uint d = get_group_id(0);
  const uint begin = offsets[d * tiles];
  const uint end = d + 1 < RS_RADIX ? offsets[(d + 1) * tiles] : n;
  uint shifts[RS_MAX_PASSES];
  uint masks[RS_MAX_PASSES];
  uint np = 0;
  for (uint p = 0; p < RS_MAX_PASSES; ++p) {
    if ((pass_mask >> p) & 1u) {
      shifts[np] = lo + p * RS_RADIX_BITS;
      masks[np] = rs_mask(shifts[np], hi_bit);
      ++np;
    }
  }
  rs_bucket_lsd(keys_a, values_a, keys_b, values_b, begin, end, 0, np, shifts, masks, hist);
}

/* The sort that stops at warp granularity (paper, section "Application in Faster Tracing
 * Kernels": the order of rays inside one warp does not change how the warp traces, so a sort may
 * "terminate bucket sorting early"). Its order, exactly: a most-significant-digit-first bucket
 * sort by 8-bit digits (RS_RADIX_BITS == 8) that splits a range of pairs by its next digit only
 * while the range holds more than `group` pairs (32: a warp); a range of `group` pairs or fewer,
 * or one with no digit left, keeps its input order. So the keys are in order except inside runs
 * of at most `group` pairs that share every digit above where their range stopped, and every
 * pair lies fewer than `group` places from where the full sort puts it. Digits that
 * are the same in every key split nothing and are stepped over (`varying`), as in the full sort.
 *
 * After the global stable pass on the top varying digit (rs_count, rs_scan, rs_scatter: keys ->
 * keys_a), one work-item per top-digit bucket walks the bucket's ranges depth first. A range
 * that splits is scattered by its digit from a into b (the same positions), where the result
 * goes (the caller's buffers), so a range that stops is already in place. lo: the lowest sorted
 * bit; digit p covers
 * [lo + 8 p, lo + 8 p + 8) below hi_bit. */
#if RS_RADIX_BITS == 8
#define RS_WARP_DEPTH ((RS_KEY_BITS + 7) / 8)

/* The varying digit (bit set in pass_mask) below pass p; RS_WARP_DEPTH when none is. */
static inline uint rs_warp_below(uint p, uint pass_mask) {
  while (p > 0 && !((pass_mask >> (p - 1)) & 1u)) --p;
  return p > 0 ? p - 1 : RS_WARP_DEPTH;
}

/* Copies [begin, end) from src to dst (a range that stops where it stands). */
static inline void rs_warp_copy(__global const rs_key* restrict src_k, __global const uint* restrict src_v,
                                __global rs_key* restrict dst_k, __global uint* restrict dst_v, uint begin, uint end) {
  for (uint i = begin; i < end; ++i) {
    dst_k[i] = src_k[i];
    dst_v[i] = src_v[i];
  }
}

/* Splits [begin, end) by the digit at `shift`: the pairs move stably from src to dst. */
static inline void rs_warp_split(__global const rs_key* restrict src_k, __global const uint* restrict src_v,
                                 __global rs_key* restrict dst_k, __global uint* restrict dst_v, uint begin, uint end,
                                 uint shift, uint mask, __local uint* restrict position) {
  for (uint d = 0; d <= mask; ++d) position[d] = 0;
  for (uint i = begin; i < end; ++i) position[rs_digit(src_k[i], shift, mask)] += 1u;
  uint running = begin;
  for (uint d = 0; d <= mask; ++d) {
    const uint c = position[d];
    position[d] = running;
    running += c;
  }
  rs_bucket_pass(src_k, src_v, dst_k, dst_v, begin, end, shift, mask, position);
}

__kernel void rs_warp_sort(__global rs_key* keys_a, __global uint* values_a, __global rs_key* keys_b,
                           __global uint* values_b, uint n, uint tiles, __global const uint* restrict offsets,
                           uint lo, uint hi_bit, uint top_pass, uint pass_mask, uint group) {
  __local uint position[RS_RADIX];
  /* Per depth: the range split there, where its next sub-range starts, the digit that split it
   * and the digit its sub-ranges split by. A sub-range is found by reading the split range's
   * digits in order (it is sorted by them), so a small range costs its own length, not a walk
   * over all RS_RADIX digit values. */
  uint cursor[RS_WARP_DEPTH], stop[RS_WARP_DEPTH], split_pass[RS_WARP_DEPTH], child_pass[RS_WARP_DEPTH];
  const uint d = get_group_id(0);
  const uint begin = offsets[d * tiles];
  const uint end = d + 1 < RS_RADIX ? offsets[(d + 1) * tiles] : n;
  uint pass = rs_warp_below(top_pass, pass_mask);
  if (end - begin <= group || pass == RS_WARP_DEPTH) {
    rs_warp_copy(keys_a, values_a, keys_b, values_b, begin, end);
    return;
  }
  /* Every split reads a and writes b, so every sub-range lies in b, where the result goes: a range
   * that splits again is first copied aside into a (one sequential copy), one that stops stays. */
  uint depth = 0;
  uint shift = lo + pass * 8u;
  rs_warp_split(keys_a, values_a, keys_b, values_b, begin, end, shift, rs_mask(shift, hi_bit), position);
  cursor[0] = begin;
  stop[0] = end;
  split_pass[0] = pass;
  child_pass[0] = rs_warp_below(pass, pass_mask);
  for (;;) {
    if (cursor[depth] == stop[depth]) {
      if (depth == 0) break;
      --depth;
      continue;
    }
    const uint split_shift = lo + split_pass[depth] * 8u, split_mask = rs_mask(split_shift, hi_bit);
    const uint sb = cursor[depth];
    const uint digit = rs_digit(keys_b[sb], split_shift, split_mask);
    uint se = sb + 1;
    while (se < stop[depth] && rs_digit(keys_b[se], split_shift, split_mask) == digit) ++se;
    cursor[depth] = se;
    pass = child_pass[depth];
    if (se - sb <= group || pass == RS_WARP_DEPTH) continue; /* stops: already in place */
    rs_warp_copy(keys_b, values_b, keys_a, values_a, sb, se);
    ++depth;
    shift = lo + pass * 8u;
    rs_warp_split(keys_a, values_a, keys_b, values_b, sb, se, shift, rs_mask(shift, hi_bit), position);
    cursor[depth] = sb;
    stop[depth] = se;
    split_pass[depth] = pass;
    child_pass[depth] = rs_warp_below(pass, pass_mask);
  }
}
#endif
#endif
