#pragma once
// A GPU cost model on top of the SIMT model (issue 20, docs/gpu-model.md): the traversal trails of
// each warp are replayed step by step through a per-SM L1 and a shared L2 (set-associative, LRU)
// over the byte addresses of the BVH layout the kernel reads, and the counts give a predicted
// trace time: issue time + memory time. Deterministic: integers from the host traversal twins.
#include <cstdint>
#include <deque>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "bvh/bvh.h"
#include "shared.h"

namespace raysort {

// One GPU, read from gpu/profiles/<name>.toml (embedded in the binary) or a .toml path.
struct GpuProfile {
  std::string name, description, origin;
  unsigned sms = 0;
  unsigned resident_warps_per_sm = 0;  // modelled occupancy: the warps interleaved on one SM
  std::uint64_t l1_bytes = 0, l2_bytes = 0;
  unsigned l1_ways = 0, l2_ways = 0, line_bytes = 0;
  unsigned sector_bytes = 0;  // the L2's and DRAM's unit: a line's sectors are filled one by one
  double dram_gbps = 0, l2_gbps = 0, clock_ghz = 0;
  double step_cycles = 0;  // SM cycles per issued warp step (the fitted constant)
  // 0: static warps of 32 consecutive rays, replayed in waves (GpuReplay::replay_wave). N > 0:
  // persistent warps with dynamic fetch (Aila and Laine's kernels): when fewer than N lanes of a warp
  // are still tracing, its finished lanes take the next rays of the trace order
  // (GpuReplay::replay_stream).
  unsigned dynamic_fetch_threshold = 0;
};

GpuProfile parse_gpu_profile(const std::string& text, const std::string& origin);
// "rtx3060" (embedded gpu/profiles/rtx3060.toml) or a path ending in .toml. Throws Error listing
// the embedded profiles for an unknown name.
GpuProfile load_gpu_profile(const std::string& name_or_path);
std::vector<std::string> gpu_profile_names();

// A set-associative cache with LRU replacement over line indices (address / line size; the L2
// model passes sector indices: its unit is the sector).
class LruCache {
 public:
  LruCache(std::uint64_t bytes, unsigned line_bytes, unsigned ways);
  bool access(std::uint64_t line);  // true on a hit; a miss allocates the line
 private:
  unsigned ways_;
  std::uint64_t sets_;
  std::vector<std::uint64_t> tags_;  // sets_ × ways_, most recently used first
};

struct GpuCounts {
  std::uint64_t warp_steps = 0;  // issued warp steps (Σ over warps of its longest trail)
  std::uint64_t idle_lanes = 0;  // lane-steps issued without work (lanes whose trail has ended)
  std::uint64_t requests = 0;    // distinct lines a warp step reads (coalesced), = L1 accesses
  std::uint64_t l1_hits = 0, l1_misses = 0;  // lines
  std::uint64_t l2_hits = 0, l2_misses = 0;  // sectors: those of an L1-missed line the lanes read
  std::uint64_t dram_bytes = 0;  // l2_misses × sector size
  // Warp steps by the slowest level one of their reads reached: the step waits for it (latency).
  std::uint64_t steps_l2 = 0;    // some read missed L1, none missed L2
  std::uint64_t steps_dram = 0;  // some read missed L2
  // The issued steps of a while-while kernel (Aila and Laine 2009) on the same trails, for
  // comparison only (gpu_model_time uses warp_steps): while_while_steps, summed over the warps.
  // Static warps only; 0 under dynamic fetch.
  std::uint64_t ww_steps = 0;
  std::uint64_t warps = 0, replayed_warps = 0;  // all warps; those replayed (sampling)
};

struct GpuTime {
  double issue_s = 0, memory_s = 0, total_s = 0;
};
// issue = warp_steps · step_cycles / (sms · clock); memory = dram_bytes / dram_bw + L2 sector
// accesses · sector / l2_bw; total = issue + memory. Counts of a sampled replay are scaled by warps / replayed.
GpuTime gpu_model_time(const GpuCounts& c, const GpuProfile& p);

// Where the kernel's buffers lie: nodes, then leaf primitives, then rays, each 4 KB aligned.
// Wide layout: a step on a wide node reads its 128 bytes; on a leaf, its packets (192 bytes each).
// Wide8 layout: the same with 256-byte nodes and 384-byte packets.
// Binary layout: a step on node k reads node k (32 bytes) and, if inner, its two children (the
// boxes it tests), if a leaf, its triangles (48 bytes each).
class GpuAddressMap {
 public:
  GpuAddressMap(const WideBvh& wide, std::size_t rays);
  GpuAddressMap(const Wide8Bvh& wide8, std::size_t rays);
  // cwbvh: an inner step reads an 80-byte node, a leaf step (RS_WIDE_LEAF | triangle << 2) one triangle.
  GpuAddressMap(const CwBvh& cw, std::size_t rays);
  GpuAddressMap(const Bvh& binary, std::size_t rays);
  // Appends the blocks (address / block_bytes: lines or sectors) step reference `ref` reads.
  // leaf_reads > 0 on a leaf: only its first leaf_reads packets (wide) or triangles (binary), where
  // an any-hit ray stopped at a hit; 0: the whole leaf.
  void step_blocks(std::uint32_t ref, unsigned block_bytes, std::vector<std::uint64_t>& out,
                   std::uint32_t leaf_reads = 0) const;
  // Appends the blocks the load of ray `ray` reads.
  void ray_blocks(std::uint32_t ray, unsigned block_bytes, std::vector<std::uint64_t>& out) const;
  // Whether step reference `ref` is a leaf (its step tests primitives) rather than an inner node.
  bool is_leaf(std::uint32_t ref) const;

 private:
  const RsBvhNode* binary_ = nullptr;  // null on the wide layouts
  std::uint64_t wide_node_bytes_ = sizeof(RsWideNode), wide_packet_bytes_ = sizeof(RsTriPacket);
  bool wide8_ = false;  // leaf references name lanes too (RS_WIDE8_LEAF_*, cl/bvh_layout.h)
  std::uint64_t node_base_ = 0, prim_base_ = 0, ray_base_ = 0;
};

// The lanes of one warp: each lane's trail and the ray it loads (rays[order[i]]). last_reads[l] > 0:
// lane l's last step is a leaf where its any-hit ray stopped at a hit, after reading that many
// packets (wide) or triangles (binary); 0 (or no entry): its last step reads the whole step.
struct WarpTrails {
  std::vector<std::vector<std::uint32_t>> lanes;
  std::vector<std::uint32_t> rays;
  std::vector<std::uint32_t> last_reads;
};

// The steps a warp issues in a while-while traversal loop (Aila and Laine 2009, "Understanding the
// efficiency of ray traversal on GPUs"): each outer iteration runs an inner-node loop until every
// lane still tracing has reached a leaf (or ended its trail), then a leaf loop until no lane has a
// leaf left. So per iteration the warp issues the longest run of consecutive inner-node steps over
// its lanes, then the longest run of consecutive leaf steps. A lockstep step of warp_steps lets a
// lane at a leaf and a lane at a node advance together; here they wait for each other. Always at
// least the longest trail.
std::uint64_t while_while_steps(const WarpTrails& warp, const GpuAddressMap& map);

// Replays the trails through the caches, in one of two schedules (docs/gpu-model.md, "Scheduling simplification" and "Other schedules").
// Static warps (replay_wave): warps are taken in trace order, sms · resident_warps_per_sm at a time
// (a wave); warp k of a wave runs on SM k mod sms; within a wave all warps advance one step per
// round, SM by SM, warp by warp, and the next wave starts when the whole wave has finished.
// Persistent warps with dynamic fetch (replay_stream, profile.dynamic_fetch_threshold > 0): the same
// sms · resident_warps_per_sm warps stay resident for the whole batch and advance one step per round
// in the same order; at its turn, a warp with fewer than the threshold lanes still tracing gives each
// finished lane the next ray of the trace order (lane order), then steps its tracing lanes.
// Caches start cold and persist to the end of the batch.
class GpuReplay {
 public:
  GpuReplay(const GpuProfile& profile, const GpuAddressMap& map);
  std::size_t wave_warps() const { return static_cast<std::size_t>(profile_.sms) * profile_.resident_warps_per_sm; }
  bool dynamic_fetch() const { return profile_.dynamic_fetch_threshold > 0; }
  void replay_wave(std::span<const WarpTrails> warps);
  // Dynamic fetch: appends the rays of `warps` (trace order; their trails are moved out) to the
  // rays still to fetch and replays as far as it can without running out of rays to fetch; `last`
  // replays to the end. Chunked calls give the counts of one call on all rays.
  void replay_stream(std::span<WarpTrails> warps, bool last);
  const GpuCounts& counts() const { return counts_; }

 private:
  struct Lane {
    std::vector<std::uint32_t> trail;
    std::uint32_t ray = 0, last_reads = 0;
    std::size_t step = 0;
  };
  void warp_step(unsigned sm, const WarpTrails& warp, std::size_t step);
  // Runs the caches on refs_ (each active lane's step reference) and sectors_ (ray loads so far).
  void issue(unsigned sm, std::uint64_t lanes);
  bool persistent_turn(std::size_t w, bool last);  // false: paused, needs more rays to fetch
  GpuProfile profile_;
  const GpuAddressMap& map_;
  std::vector<LruCache> l1_;
  LruCache l2_;
  GpuCounts counts_;
  std::vector<std::uint64_t> sectors_;
  std::vector<std::uint64_t> refs_;  // (leaf reads << 32) | step reference
  // Dynamic fetch state, kept across replay_stream calls.
  std::vector<std::vector<Lane>> resident_;  // warp → its lanes; a lane traces while step < trail.size()
  std::deque<Lane> to_fetch_;
  std::size_t next_warp_ = 0;  // the warp whose turn is next in the current round
  bool any_stepped_ = false;   // some warp stepped in the current round
};

}  // namespace raysort
