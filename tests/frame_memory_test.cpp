// Memory is estimated before work starts (issue 23, item 2): sizes a user can type that do not fit
// end in one line and exit 2, at once and before allocating; the estimate stays above what a run
// really takes (so a frame that passes the check does not run the machine out of memory).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "render/frame_memory.h"
#include "scene/load.h"
#include "test_util.h"

using namespace raysort;

using Measured = raysort::testing::CliResult;
using raysort::testing::run_cli;

TEST(FrameMemory, ModelCountsEveryBatchTheEffectsImply) {
  // cornell's effects: 1 bounce, 1 shadow ray per bounce: primary, shadow0, bounce1, shadow1.
  const FrameMemory m = estimate_frame_memory(100, 10, 2, 1, 1);
  EXPECT_EQ(m.paths, 2000u);
  EXPECT_EQ(m.rays, 8000u);
  EXPECT_EQ(m.largest_batch, 2000u);
  EXPECT_EQ(estimate_frame_memory(100, 10, 2, 4, 1).rays, 2000u + 8000u + 2000u + 8000u);
  EXPECT_EQ(estimate_frame_memory(100, 10, 2, 0, 3).rays, 4 * 2000u);  // no lights: primary + 3 bounces
  // Sizes past 64 bits saturate instead of wrapping into a small estimate.
  const FrameMemory huge = estimate_frame_memory(4000000000u, 4000000000u, 4000000000u, 1, 1);
  EXPECT_EQ(huge.paths, std::numeric_limits<std::uint64_t>::max());
  EXPECT_THROW(check_frame_memory(huge, nullptr, "huge"), ResourceError);
  EXPECT_NO_THROW(check_frame_memory(estimate_frame_memory(16, 16, 1, 1, 1), nullptr, "tiny"));
}

// The two commands of the issue, and the other commands that allocate per ray: exit 2, one line,
// under 5 s, before allocating (peak RSS under 500 MB).
TEST(FrameMemory, OversizedCommandsAreRefusedAtOnce) {
  const std::string out = raysort::testing::temp_path("oversized");
  const std::vector<std::vector<std::string>> commands{
      {"trace", "--scene", "cornell", "--resolution", "20000x20000"},
      {"run", "--scenes", "cornell", "--encoders", "hcc", "--resolution", "64x64", "--spp", "1000000", "--out", out},
      {"render", "--scene", "cornell", "--resolution", "20000x20000", "--out", out},
      {"encodebench", "--scene", "cornell", "--resolution", "20000x20000"},
      {"trace", "--scene", "cornell", "--resolution", "4000000000x4000000000", "--spp", "4000000000"},
  };
  for (const auto& args : commands) {
    // A render splits its rays into passes, so only its per-pixel sums (≈ 36 GiB at 20000x20000)
    // can refuse it: the host's memory is fixed at 16 GiB here, so that this holds on any machine.
    const bool render = args[0] == "render";
    const Measured m = run_cli(args, render ? std::vector<std::string>{"RAYSORT_TEST_HOST_MEMORY_BYTES=17179869184"}
                                            : std::vector<std::string>{});
    const std::string cmd = args[0] + " " + args[4];
    EXPECT_EQ(m.code, 2) << cmd << ": " << m.err;
    EXPECT_EQ(std::count(m.err.begin(), m.err.end(), '\n'), 1) << cmd << ": " << m.err;
    for (const char* part : {"scene cornell at ", "needs ", "over ", render ? "lower --resolution (a render keeps sums for every pixel"
                                                                           : "lower --resolution or --spp"})
      EXPECT_NE(m.err.find(part), std::string::npos) << cmd << ": no '" << part << "' in " << m.err;
    EXPECT_LT(m.seconds, 5.0) << cmd;
    EXPECT_LT(m.peak_rss_bytes, 500u << 20) << cmd;
    EXPECT_FALSE(std::filesystem::exists(out)) << cmd << ": wrote " << out;
  }
  // The host limit: a frame that fits the device but not the memory left on the host.
  const Measured host = run_cli({"trace", "--scene", "cornell", "--resolution", "1024x1024"},
                                     {"RAYSORT_TEST_HOST_MEMORY_BYTES=100000000"});
  EXPECT_EQ(host.code, 2) << host.err;
  EXPECT_NE(host.err.find("of host memory (the CPU device's buffers included)"), std::string::npos) << host.err;
  EXPECT_NE(host.err.find("over the 95.4 MiB available"), std::string::npos) << host.err;
}

// A CPU device's buffers are host memory: they are checked against the host's free memory, not
// against the global memory size the driver reports. PoCL reports 3/4 of hwloc's NUMA-node
// memory, 4.7 GiB on a 24 GiB machine whose container shows a 6.2 GiB node, and allocates past it;
// the paper preset's largest batch (33.2 M shadow rays, ≈ 4.9 GiB of buffers) runs there. A GPU
// reporting the same size is refused, naming its global memory.
TEST(FrameMemory, CpuDeviceBuffersAreHostMemoryNotTheReportedGlobalSize) {
  const FrameMemory paper = estimate_frame_memory(1920, 1080, 8, 2, 1);
  DeviceInfo device;
  device.name = "pthread-test";
  device.global_mem_bytes = 5003443200;  // what PoCL 3.1 reported on that machine
  device.max_alloc_bytes = 2ull << 30;
  ASSERT_GT(paper.device_bytes, device.global_mem_bytes);
  ASSERT_LT(paper.largest_buffer_bytes, device.max_alloc_bytes);
  // The refusal's text for a host of `host_gib` GiB free, or "" when the frame is accepted.
  auto refusal = [&](const char* type, const char* host_gib) -> std::string {
    device.type = type;
    const std::string bytes = std::to_string(std::stoull(host_gib) << 30);
    setenv("RAYSORT_TEST_HOST_MEMORY_BYTES", bytes.c_str(), 1);
    std::string what;
    try {
      check_frame_memory(paper, &device, "paper preset");
    } catch (const ResourceError& e) {
      what = e.what();
    }
    unsetenv("RAYSORT_TEST_HOST_MEMORY_BYTES");
    return what;
  };
  ASSERT_LT(paper.host_bytes + paper.device_bytes, 16ull << 30);
  EXPECT_EQ(refusal("CPU", "16"), "");
  // A smaller host: refused by the host's memory, never by the reported size.
  EXPECT_NE(refusal("CPU", "8").find("of host memory (the CPU device's buffers included)"), std::string::npos);
  EXPECT_NE(refusal("GPU", "16").find("over the device's global memory of 4.7 GiB (pthread-test)"), std::string::npos);
}

// A scene file whose mesh would not fit (scene/load.h, SceneOptions::max_triangles; the parser's
// side is tests/scene_test.cpp): exit 2 and one line, like a frame that does not fit.
TEST(FrameMemory, OversizedSceneFileEndsACommandWithExit2) {
  const std::string dir = raysort::testing::temp_path("oversized-scene");
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/terrain.toml";
  std::ofstream(file) << "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n\n[[mesh]]\n"
                          "name = \"terrain\"\n\ngenerator = \"heightfield\"\n[mesh.params]\nresolution = 8192\n";
  const Measured m = run_cli({"trace", "--scene", file});
  EXPECT_EQ(m.code, 2) << m.err;
  EXPECT_EQ(std::count(m.err.begin(), m.err.end(), '\n'), 1) << m.err;
  EXPECT_NE(m.err.find("terrain.toml:8: the scene would hold 134217728 triangles"), std::string::npos) << m.err;
  EXPECT_LT(m.seconds, 5.0);
  EXPECT_LT(m.peak_rss_bytes, 500u << 20);
}

// A render traces its rays in passes (render/preview.h): its estimate follows the largest pass and
// the pixels, not the samples, so the 64-spp full-HD frame the whole-frame model refuses (≈ 20 GiB
// of a CPU device's memory) fits, and a million samples cost no more memory than one.
TEST(FrameMemory, RenderIsSizedByItsPassesNotItsSamples) {
  Scene scene = load_scene("cornell");
  apply_frame_size(scene, {1920, 1080, 64});
  const FrameMemory frame = estimate_frame_memory(scene), render = estimate_render_memory(scene);
  EXPECT_EQ(render.largest_batch, 1920u * 1080u);  // one sample of every pixel per pass
  EXPECT_GE(render.host_bytes, 1920u * 1080u * FrameMemory::kRenderHostPerPixel);
  EXPECT_LT(render.host_bytes + render.device_bytes, (frame.host_bytes + frame.device_bytes) / 20);
  EXPECT_NO_THROW(check_frame_memory(render, nullptr, "render"));
  apply_frame_size(scene, {1920, 1080, 1000000});
  EXPECT_EQ(estimate_render_memory(scene).host_bytes, render.host_bytes);
  // Past the pass budget in pixels: passes of whole rows of one sample.
  apply_frame_size(scene, {7680, 4320, 4});
  EXPECT_EQ(estimate_render_memory(scene).largest_batch, 273u * 7680u);
}

// The estimate is an upper bound of what the commands take: the peak RSS a frame adds over a tiny
// one stays below the estimated difference (host and, on a CPU device, its buffers).
TEST(FrameMemory, EstimateBoundsWhatTheCommandsTake) {
  const std::string out = raysort::testing::temp_path("bound");
  auto args_at = [&](const std::string& cmd, const std::string& resolution,
                     const std::string& tag = "") -> std::vector<std::string> {
    if (cmd == "run")
      return {"run", "--scenes", "cornell", "--encoders", "hcc,costa", "--bits", "64", "--access", "gather,permute",
              "--variant", "both", "--resolution", resolution, "--reps", "1", "--warmup", "0", "--max-time", "0",
              "--out", out + tag + "-" + resolution};
    if (cmd == "render")
      return {"render", "--scene", "cornell", "--resolution", resolution, "--out", out + tag + "-img-" + resolution};
    return {"trace", "--scene", "cornell", "--variant", "both", "--resolution", resolution, "--reps", "1", "--warmup",
            "0", "--max-time", "0"};
  };
  for (const std::string cmd : {"run", "trace", "render"}) {
    // Once untimed first, at both sizes: a cold PoCL kernel cache makes a command compile its kernels
    // in process (LLVM's memory in its peak RSS), and PoCL compiles a kernel apart for small grids (the
    // "smallgrid" entries of its cache), so after a warm-up at 64x64 alone the 640x640 frame still
    // compiled (on a cold cache `run` grew 229.9 MiB against 205 warm, its bound 235.1).
    (void)run_cli(args_at(cmd, "64x64", "-warm"));
    (void)run_cli(args_at(cmd, "640x640", "-warm"));
    const Measured small = run_cli(args_at(cmd, "64x64"));
    const Measured large = run_cli(args_at(cmd, "640x640"));
    ASSERT_EQ(small.code, 0) << small.err;
    ASSERT_EQ(large.code, 0) << large.err;
    auto estimate = [&](std::uint32_t side) {
      if (cmd != "render") return estimate_frame_memory(side, side, 1, 1, 1);
      Scene scene = load_scene("cornell");
      apply_frame_size(scene, {side, side, 1});
      return estimate_render_memory(scene);
    };
    const FrameMemory a = estimate(64), b = estimate(640);
    const std::uint64_t estimated = (b.host_bytes + b.device_bytes) - (a.host_bytes + a.device_bytes);
    const std::uint64_t taken = large.peak_rss_bytes - small.peak_rss_bytes;
    std::cout << cmd << " 64x64 -> 640x640: peak RSS grew " << format_bytes(taken) << ", estimated "
              << format_bytes(estimated) << "\n";
    EXPECT_LT(taken, estimated) << cmd << ": took " << format_bytes(taken) << ", estimated " << format_bytes(estimated);
    EXPECT_GT(taken, estimated / 3) << cmd << ": the estimate is far too high to be useful (" << format_bytes(taken)
                                    << " taken, " << format_bytes(estimated) << " estimated)";
  }
}
