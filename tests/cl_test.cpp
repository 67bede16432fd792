// The OpenCL runtime: device choice, error names, build failures that surface the log.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "test_util.h"

namespace raysort {

TEST(ClRuntime, ListsAtLeastOneDevice) {
  auto devices = list_devices();
  ASSERT_FALSE(devices.empty()) << "no OpenCL device: is pocl-opencl-icd installed?";
  for (auto& d : devices) {
    EXPECT_FALSE(d.name.empty());
    EXPECT_GT(d.compute_units, 0u);
    EXPECT_GT(d.max_alloc_bytes, 0u);
  }
}

TEST(ClRuntime, SelectsByIndexTypeAndName) {
  auto devices = list_devices();
  ASSERT_FALSE(devices.empty());
  EXPECT_EQ(select_device("0").index, 0);
  auto by_type = select_device(devices[0].type == "GPU" ? "gpu" : "cpu");
  EXPECT_EQ(by_type.type, devices[0].type);
  auto by_name = select_device(devices[0].name.substr(0, 4));
  EXPECT_EQ(by_name.index, 0);
}

TEST(ClRuntime, UnknownDeviceListsTheValidOnes) {
  try {
    select_device("no-such-device-xyz");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("no-such-device-xyz"), std::string::npos) << msg;
    EXPECT_NE(msg.find(list_devices()[0].name), std::string::npos) << msg;
  }
  EXPECT_THROW(select_device("999"), Error);
}

TEST(ClRuntime, ErrorNames) {
  EXPECT_EQ(cl_error_name(CL_OUT_OF_RESOURCES), "CL_OUT_OF_RESOURCES");
  EXPECT_EQ(cl_error_name(CL_BUILD_PROGRAM_FAILURE), "CL_BUILD_PROGRAM_FAILURE");
  EXPECT_EQ(cl_error_name(-12345), "CL_UNKNOWN_ERROR(-12345)");
}

TEST(ClRuntime, BuildFailureSurfacesTheLogAndOptions) {
  Runtime& rt = testing::runtime();
  try {
    rt.build_source("__kernel void broken(__global int* p) { p[0] = undeclared_identifier_q; }", "broken.cl", "-DFOO=1");
    FAIL() << "expected the build to fail";
  } catch (const ClError& e) {
    std::string msg = e.what();
    EXPECT_EQ(e.code(), CL_BUILD_PROGRAM_FAILURE);
    EXPECT_NE(msg.find("broken.cl"), std::string::npos) << msg;
    EXPECT_NE(msg.find("undeclared_identifier_q"), std::string::npos) << "build log missing:\n" << msg;
    EXPECT_NE(msg.find("-DFOO=1"), std::string::npos) << "options missing:\n" << msg;
    EXPECT_NE(msg.find(rt.info().name), std::string::npos) << "device missing:\n" << msg;
  }
}

TEST(ClRuntime, OversizedAllocationNamesBufferAndLimit) {
  Runtime& rt = testing::runtime();
  try {
    rt.buffer("giant rays", rt.info().max_alloc_bytes + 1);
    FAIL() << "expected an allocation error";
  } catch (const ClError& e) {
    std::string msg = e.what();
    EXPECT_NE(msg.find("giant rays"), std::string::npos) << msg;
    EXPECT_NE(msg.find("maximum allocation"), std::string::npos) << msg;
  }
}

// rs4_bits (cl/lanes.h) is one movmskps on x86 devices and an AND/OR form elsewhere: on the device,
// both give lane i -> bit i for each of the sixteen -1/0 masks, and the x86 form is the one PoCL
// builds here (a test that could only ever see the portable form would check nothing new). The
// sixteen- and eight-lane forms (rs16_mask_bits, rs8_mask_bits: one instruction on AVX-512 devices) on bit patterns,
// and the lowest set bit (rs_lowest_bit[_u|_ul]: tzcnt on x86 devices, clz of the isolated bit elsewhere).
TEST(ClRuntime, MaskBitsFormsAgree) {
  Runtime& rt = testing::runtime();
  const std::string src = kernel_source("cl/lanes.h") + R"(
__kernel void mask_bits(__global int* out) {
  const int i = get_global_id(0);
  const int4 m = (int4)((i & 1) ? -1 : 0, (i & 2) ? -1 : 0, (i & 4) ? -1 : 0, (i & 8) ? -1 : 0);
  out[3 * i] = rs4_bits(m);
  out[3 * i + 1] = rs4_bits_portable(m);
  out[3 * i + 2] = RS_MASK_BITS_MOVMSK;
}
/* Sixteen- and eight-lane masks from bit patterns p (lane l set when bit l of p is):
 * rs16_mask_bits and rs8_mask_bits must give p back; and rs_lowest_bit[_u|_ul] of p at three places. */
__kernel void mask_bits16(__global const uint* patterns, __global uint* out) {
  const int i = get_global_id(0);
  const uint p = patterns[i];
  const int16 lanes = (int16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const int16 m = ((int16)(p) >> lanes & 1) != 0;
  out[6 * i] = rs16_mask_bits(m);
  out[6 * i + 1] = rs8_mask_bits(m.lo) | (rs8_mask_bits(m.hi) << 8);
  /* The lowest set bit (x != 0) of p and of p moved to the top of 32 and 64 bits. */
  const uint top = p ? p << 16 : 0x80000000u;
  const ulong high = p ? (ulong)p << 48 : 0x8000000000000000ul;
  const ulong middle = p ? (ulong)p << 20 : 1ul;
  out[6 * i + 2] = p ? (uint)rs_lowest_bit((int)p) : 99u;
  out[6 * i + 3] = (uint)rs_lowest_bit_u(top);
  out[6 * i + 4] = (uint)rs_lowest_bit_ul(high);
  out[6 * i + 5] = (uint)rs_lowest_bit_ul(middle);
}
)";
  cl::Program program = rt.build_source(src, "mask_bits.cl");
  cl::Buffer out = rt.buffer("mask bits", 16 * 3 * sizeof(int));
  cl_call("mask_bits", [&] {
    cl::Kernel k(program, "mask_bits");
    k.setArg(0, out);
    rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(16), cl::NDRange(16));
  });
  std::vector<int> v;
  rt.download("mask bits", out, v, 16 * 3);
  for (int i = 0; i < 16; ++i) {
    EXPECT_EQ(v[3 * i], i) << "rs4_bits";
    EXPECT_EQ(v[3 * i + 1], i) << "rs4_bits_portable";
  }
#if defined(__x86_64__)
  if (rt.info().is_pocl() && rt.info().type == "CPU") {
    EXPECT_EQ(v[2], 1) << "PoCL on x86 should build the movmskps form";
  }
#endif

  std::vector<std::uint32_t> patterns = {0u, 0xFFFFu, 0x8000u, 0x0001u, 0x00FFu, 0xFF00u, 0x5555u, 0xAAAAu};
  for (std::uint32_t p = 1; p < 0x10000u; p = p * 7u + 3u) patterns.push_back(p & 0xFFFFu);
  cl::Buffer pattern_buf = rt.upload("patterns", patterns);
  // Every form of the sixteen- and eight-lane helpers: the device's own, and the others built on
  // purpose: the portable one and the AVX form (two vmovmskps, what an AVX2 CPU's PoCL builds; on an
  // x86 CPU device only).
  std::vector<std::string> forms{"", "-DRS_PORTABLE_MASK_BITS"};
  if (rt.info().is_pocl() && rt.info().type == "CPU") forms.push_back("-DRS_AVX_MASK_BITS");
  for (const std::string& options : forms) {
    cl::Program form = options.empty() ? program : rt.build_source(src, "mask_bits.cl", options);
    cl::Buffer out16 = rt.buffer("mask bits 16", patterns.size() * 6 * sizeof(std::uint32_t));
    cl_call("mask_bits16", [&] {
      cl::Kernel k(form, "mask_bits16");
      k.setArg(0, pattern_buf);
      k.setArg(1, out16);
      rt.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(patterns.size()), cl::NullRange);
    });
    std::vector<std::uint32_t> w;
    rt.download("mask bits 16", out16, w, patterns.size() * 6);
    for (std::size_t i = 0; i < patterns.size(); ++i) {
      const std::uint32_t p = patterns[i];
      EXPECT_EQ(w[6 * i], p) << options << ": rs16_mask_bits of pattern " << std::hex << p;
      EXPECT_EQ(w[6 * i + 1], p) << options << ": rs8_mask_bits of pattern " << std::hex << p;
      const std::uint32_t low = p ? static_cast<std::uint32_t>(std::countr_zero(p)) : 99u;
      EXPECT_EQ(w[6 * i + 2], low) << options << ": rs_lowest_bit of " << std::hex << p;
      EXPECT_EQ(w[6 * i + 3], p ? low + 16 : 31u) << options << ": rs_lowest_bit_u of " << std::hex << (p << 16);
      EXPECT_EQ(w[6 * i + 4], p ? low + 48 : 63u) << options << ": rs_lowest_bit_ul of " << std::hex << p << " << 48";
      EXPECT_EQ(w[6 * i + 5], p ? low + 20 : 0u) << options << ": rs_lowest_bit_ul of " << std::hex << p << " << 20";
    }
  }
}

// RAYSORT_CL_OPTIONS reaches every kernel build (the way to the portable mask-bit forms on an x86
// compiler without the target builtins): a source that needs its macro builds only with it.
TEST(ClRuntime, ClOptionsFromTheEnvironmentReachTheBuild) {
  Runtime& rt = testing::runtime();
  const std::string src =
      "#ifndef RS_TEST_OPTION_SEEN\n#error RS_TEST_OPTION_SEEN is not defined\n#endif\n"
      "__kernel void seen(__global int* p) { p[0] = RS_TEST_OPTION_SEEN; }\n";
  EXPECT_THROW(rt.build_source(src, "seen.cl"), Error);
  ::setenv("RAYSORT_CL_OPTIONS", "-DRS_TEST_OPTION_SEEN=7", 1);
  EXPECT_NE(rt.build_options("").find("-DRS_TEST_OPTION_SEEN=7"), std::string::npos);
  EXPECT_NO_THROW(rt.build_source(src, "seen.cl"));
  ::unsetenv("RAYSORT_CL_OPTIONS");
}

// On a CPU device the trace kernels prefetch the rays they gather (cl/trace.cl, "Gather on a CPU"):
// the build defines how far ahead, and the kernels compile with it. A GPU build never gets it.
TEST(ClRuntime, CpuBuildsPrefetchTheGatheredRays) {
  Runtime& rt = testing::runtime();
  const bool cpu = rt.info().type == "CPU" || rt.info().is_simulator();
  EXPECT_EQ(rt.build_options("").find("-DRS_PREFETCH_AHEAD=") != std::string::npos, cpu) << rt.info().type;
  if (!cpu) GTEST_SKIP() << "a " << rt.info().type << " device: no prefetch";
  const std::string src =
      "#if !defined(RS_PREFETCH_AHEAD) || RS_PREFETCH_AHEAD < 1\n#error no prefetch distance\n#endif\n"
      "__kernel void ahead(__global int* p) { p[0] = RS_PREFETCH_AHEAD; }\n";
  EXPECT_NO_THROW(rt.build_source(src, "ahead.cl"));
}

TEST(ClRuntime, EmbeddedKernelsResolveIncludes) {
  std::string src = kernel_source("cl/trace.cl");
  EXPECT_NE(src.find("RAYSORT_SHARED_H"), std::string::npos);
  EXPECT_NE(src.find("rs_traverse"), std::string::npos);
  EXPECT_EQ(src.find("#include \""), std::string::npos) << "unresolved include left in the source";
}

}  // namespace raysort
