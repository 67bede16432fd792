// The OpenCL runtime: device choice, error names, build failures that surface the log.
#include <gtest/gtest.h>

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

TEST(ClRuntime, EmbeddedKernelsResolveIncludes) {
  std::string src = kernel_source("cl/trace.cl");
  EXPECT_NE(src.find("RAYSORT_SHARED_H"), std::string::npos);
  EXPECT_NE(src.find("rs_traverse"), std::string::npos);
  EXPECT_EQ(src.find("#include \""), std::string::npos) << "unresolved include left in the source";
}

}  // namespace raysort
