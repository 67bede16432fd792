#include "runtime/runtime.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "shared.h"
#include "util/embedded.h"
#include "util/fnv.h"
#include "util/input_file.h"

namespace raysort {

namespace {

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  return s.substr(b);
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string type_name(cl_device_type t) {
  if (t & CL_DEVICE_TYPE_GPU) return "GPU";
  if (t & CL_DEVICE_TYPE_CPU) return "CPU";
  if (t & CL_DEVICE_TYPE_ACCELERATOR) return "ACCELERATOR";
  return "OTHER";
}

std::string& kernel_dir() {
  static std::string dir;
  return dir;
}

std::string read_kernel_file(const std::string& path) {
  if (!kernel_dir().empty()) {
    // --kernels DIR points at a cl/ folder (or the repository root holding one).
    // Read through the shared input reader (util/input_file.h): a FIFO under DIR would block the
    // read forever, a device read without end. An empty file is refused naming it: OpenCL would
    // only say CL_INVALID_KERNEL_NAME later, without the file.
    for (const std::string& candidate :
         {kernel_dir() + "/" + path.substr(path.find('/') + 1), kernel_dir() + "/" + path}) {
      std::error_code ec;
      if (!std::filesystem::exists(candidate, ec)) continue;
      std::string text = read_input_file(candidate, kKernelFile);
      if (text.find_first_not_of(" \t\r\n") == std::string::npos)
        throw Error(fmt::format("kernel file {} (for {}) is empty; point --kernels at the repository's cl/ folder, or "
                                "restore the file",
                                candidate, path));
      return text;
    }
    throw Error(fmt::format("kernel file '{}' not found under --kernels {}; point it at the repository's cl/ folder",
                            path, kernel_dir()));
  }
  auto e = find_embedded(path);
  if (!e) throw Error(fmt::format("kernel file '{}' is not embedded in this binary (rebuild raysort)", path));
  return std::string(*e);
}

// Whether a kernel header opens with an include guard (its first two directives #ifndef X, #define X),
// so that a second inclusion would add nothing.
bool has_include_guard(const std::string& text) {
  std::istringstream in(text);
  std::string line, guard;
  while (std::getline(in, line)) {
    const auto p = line.find_first_not_of(" \t");
    if (p == std::string::npos || line[p] != '#') continue;
    std::istringstream words(line.substr(p + 1));
    std::string directive, name;
    words >> directive >> name;
    if (guard.empty()) {
      if (directive != "ifndef") return false;
      guard = name;
    } else {
      return directive == "define" && name == guard;
    }
  }
  return false;
}

// Inlines the #include "..." lines of a kernel file. A guarded header is inlined once (the rest
// would be empty); an unguarded one wherever it is included, as a preprocessor would: the
// width-generic traversal (traverse_wide_w.h) is included once per width in a wide8 build.
void resolve_includes(const std::string& path, std::string& out, std::set<std::string>& seen) {
  const std::string text = read_kernel_file(path);
  if (has_include_guard(text) && !seen.insert(path).second) return;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  out += fmt::format("#line 1 \"{}\"\n", path);
  while (std::getline(in, line)) {
    ++line_no;
    auto pos = line.find("#include \"");
    if (pos != std::string::npos && line.find_first_not_of(" \t") == pos) {
      auto end = line.find('"', pos + 10);
      std::string inc = "cl/" + line.substr(pos + 10, end - pos - 10);
      resolve_includes(inc, out, seen);
      out += fmt::format("#line {} \"{}\"\n", line_no + 1, path);
      continue;
    }
    out += line;
    out += '\n';
  }
}

}  // namespace

std::string cl_error_name(cl_int code) {
  switch (code) {
#define RS_CASE(x) \
  case x:          \
    return #x;
    RS_CASE(CL_SUCCESS)
    RS_CASE(CL_DEVICE_NOT_FOUND)
    RS_CASE(CL_DEVICE_NOT_AVAILABLE)
    RS_CASE(CL_COMPILER_NOT_AVAILABLE)
    RS_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    RS_CASE(CL_OUT_OF_RESOURCES)
    RS_CASE(CL_OUT_OF_HOST_MEMORY)
    RS_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
    RS_CASE(CL_MEM_COPY_OVERLAP)
    RS_CASE(CL_IMAGE_FORMAT_MISMATCH)
    RS_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    RS_CASE(CL_BUILD_PROGRAM_FAILURE)
    RS_CASE(CL_MAP_FAILURE)
    RS_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    RS_CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
    RS_CASE(CL_COMPILE_PROGRAM_FAILURE)
    RS_CASE(CL_LINKER_NOT_AVAILABLE)
    RS_CASE(CL_LINK_PROGRAM_FAILURE)
    RS_CASE(CL_DEVICE_PARTITION_FAILED)
    RS_CASE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
    RS_CASE(CL_INVALID_VALUE)
    RS_CASE(CL_INVALID_DEVICE_TYPE)
    RS_CASE(CL_INVALID_PLATFORM)
    RS_CASE(CL_INVALID_DEVICE)
    RS_CASE(CL_INVALID_CONTEXT)
    RS_CASE(CL_INVALID_QUEUE_PROPERTIES)
    RS_CASE(CL_INVALID_COMMAND_QUEUE)
    RS_CASE(CL_INVALID_HOST_PTR)
    RS_CASE(CL_INVALID_MEM_OBJECT)
    RS_CASE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
    RS_CASE(CL_INVALID_IMAGE_SIZE)
    RS_CASE(CL_INVALID_SAMPLER)
    RS_CASE(CL_INVALID_BINARY)
    RS_CASE(CL_INVALID_BUILD_OPTIONS)
    RS_CASE(CL_INVALID_PROGRAM)
    RS_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
    RS_CASE(CL_INVALID_KERNEL_NAME)
    RS_CASE(CL_INVALID_KERNEL_DEFINITION)
    RS_CASE(CL_INVALID_KERNEL)
    RS_CASE(CL_INVALID_ARG_INDEX)
    RS_CASE(CL_INVALID_ARG_VALUE)
    RS_CASE(CL_INVALID_ARG_SIZE)
    RS_CASE(CL_INVALID_KERNEL_ARGS)
    RS_CASE(CL_INVALID_WORK_DIMENSION)
    RS_CASE(CL_INVALID_WORK_GROUP_SIZE)
    RS_CASE(CL_INVALID_WORK_ITEM_SIZE)
    RS_CASE(CL_INVALID_GLOBAL_OFFSET)
    RS_CASE(CL_INVALID_EVENT_WAIT_LIST)
    RS_CASE(CL_INVALID_EVENT)
    RS_CASE(CL_INVALID_OPERATION)
    RS_CASE(CL_INVALID_GL_OBJECT)
    RS_CASE(CL_INVALID_BUFFER_SIZE)
    RS_CASE(CL_INVALID_MIP_LEVEL)
    RS_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
    RS_CASE(CL_INVALID_PROPERTY)
    RS_CASE(CL_INVALID_IMAGE_DESCRIPTOR)
    RS_CASE(CL_INVALID_COMPILER_OPTIONS)
    RS_CASE(CL_INVALID_LINKER_OPTIONS)
    RS_CASE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef RS_CASE
    case -1001:
      return "CL_PLATFORM_NOT_FOUND_KHR (no OpenCL driver installed: run scripts/install-deps.sh for PoCL)";
    default:
      return fmt::format("CL_UNKNOWN_ERROR({})", code);
  }
}

std::string human_bytes(std::uint64_t b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(b);
  int u = 0;
  while (v >= 1024.0 && u < 4) {
    v /= 1024.0;
    ++u;
  }
  return u == 0 ? fmt::format("{} B", b) : fmt::format("{:.1f} {}", v, units[u]);
}

std::string DeviceInfo::slug() const {
  std::string s = (is_pocl() ? "pocl-" : "") + lower(type) + "-" + lower(name);
  std::string out;
  for (char c : s) {
    if (std::isalnum(static_cast<unsigned char>(c))) out += c;
    else if (!out.empty() && out.back() != '-') out += '-';
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  if (out.size() > 48) out.resize(48);
  return out;
}

std::vector<DeviceInfo> list_devices() {
  std::vector<cl::Platform> platforms;
  // Zero platforms is an answer (select_device says what to install), not a fault: the ICD loader
  // returns CL_PLATFORM_NOT_FOUND_KHR when no driver is registered (or OCL_ICD_VENDORS names an
  // empty folder), which the C++ bindings throw as cl::Error "clGetPlatformIDs".
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error&) {
    platforms.clear();
  }
  std::vector<DeviceInfo> out;
  for (auto& p : platforms) {
    std::vector<cl::Device> devices;
    try {
      p.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;  // a platform with no devices
    }
    for (auto& d : devices) {
      DeviceInfo i;
      i.index = static_cast<int>(out.size());
      i.platform = p;
      i.device = d;
      i.platform_name = trim(p.getInfo<CL_PLATFORM_NAME>());
      i.platform_version = trim(p.getInfo<CL_PLATFORM_VERSION>());
      i.name = trim(d.getInfo<CL_DEVICE_NAME>());
      i.type = type_name(d.getInfo<CL_DEVICE_TYPE>());
      i.version = trim(d.getInfo<CL_DEVICE_VERSION>());
      i.driver_version = trim(d.getInfo<CL_DRIVER_VERSION>());
      i.opencl_c_version = trim(d.getInfo<CL_DEVICE_OPENCL_C_VERSION>());
      i.compute_units = d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
      i.global_mem_bytes = d.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
      i.local_mem_bytes = d.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
      i.max_alloc_bytes = d.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
      i.max_work_group_size = d.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
      i.correctly_rounded_divide_sqrt =
          (d.getInfo<CL_DEVICE_SINGLE_FP_CONFIG>() & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) != 0;
      i.preferred_float_width = d.getInfo<CL_DEVICE_PREFERRED_VECTOR_WIDTH_FLOAT>();
      i.native_float_width = d.getInfo<CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT>();
      out.push_back(std::move(i));
    }
  }
  return out;
}

DeviceInfo select_device(std::string spec) {
  if (spec.empty())
    if (const char* env = std::getenv("RAYSORT_DEVICE")) spec = env;
  auto devices = list_devices();
  if (devices.empty())
    throw Error(
        "no OpenCL device found: no OpenCL driver (ICD) is installed, or none has a device; install PoCL for CPUs "
        "(`apt-get install pocl-opencl-icd`, or scripts/install-deps.sh) or a GPU vendor's driver, and check with "
        "`clinfo -l` (OCL_ICD_VENDORS, when set, must name the folder of the .icd files)");
  auto listing = [&] {
    std::string s;
    // On one line, as every error is (docs/errors.md).
    for (auto& d : devices) s += fmt::format("{} [{}] {} / {} ({})", s.empty() ? "" : ";", d.index, d.platform_name, d.name, d.type);
    return s;
  };
  // The first device of `type` ("" for any), real hardware before simulators and single-threaded ones.
  auto first_of = [&](const std::string& type) -> const DeviceInfo* {
    for (bool preferred : {true, false})
      for (auto& d : devices)
        if (d.is_preferred() == preferred && (type.empty() || d.type == type)) return &d;
    return nullptr;
  };
  if (spec.empty()) {
    for (const DeviceInfo* d : {first_of("GPU"), first_of("CPU")})
      if (d && d->is_preferred()) return *d;
    return *first_of("");
  }
  std::string ls = lower(spec);
  if (std::all_of(spec.begin(), spec.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
    // Any run of digits is an index; one too long for a number is as much past the list as 12 is.
    std::size_t idx = 0;
    const auto [end, ec] = std::from_chars(spec.data(), spec.data() + spec.size(), idx);
    if (ec == std::errc() && end == spec.data() + spec.size() && idx < devices.size()) return devices[idx];
    throw Error(fmt::format("--device {}: no device with that index; {}:{}", spec,
                            devices.size() == 1 ? std::string("the one device is [0]")
                                                : fmt::format("the {} devices are [0] to [{}]", devices.size(), devices.size() - 1),
                            listing()));
  }
  if (ls == "gpu" || ls == "cpu") {
    if (const DeviceInfo* d = first_of(ls == "gpu" ? "GPU" : "CPU")) return *d;
    throw Error(fmt::format("--device {}: no {} device; devices are:{}", spec, ls, listing()));
  }
  for (auto& d : devices)
    if (lower(d.name).find(ls) != std::string::npos || lower(d.platform_name).find(ls) != std::string::npos) return d;
  throw Error(fmt::format("--device {}: no device name contains '{}'; devices are:{}", spec, spec, listing()));
}

void set_kernel_dir(std::string dir) { kernel_dir() = std::move(dir); }

std::string kernel_source(const std::string& path) {
  std::string out;
  std::set<std::string> seen;
  resolve_includes(path, out, seen);
  return out;
}

double event_ms(const cl::Event& e) {
  auto start = e.getProfilingInfo<CL_PROFILING_COMMAND_START>();
  auto end = e.getProfilingInfo<CL_PROFILING_COMMAND_END>();
  return static_cast<double>(end - start) * 1e-6;
}

double event_span_ms(const cl::Event& first, const cl::Event& last) {
  auto start = first.getProfilingInfo<CL_PROFILING_COMMAND_START>();
  auto end = last.getProfilingInfo<CL_PROFILING_COMMAND_END>();
  return static_cast<double>(end - start) * 1e-6;
}

Runtime::Runtime(DeviceInfo info) : info_(std::move(info)) {
  cl_call("creating a context on " + info_.name, [&] { context_ = cl::Context(info_.device); });
  cl_call("creating a profiling command queue on " + info_.name,
          [&] { queue_ = cl::CommandQueue(context_, info_.device, CL_QUEUE_PROFILING_ENABLE); });
}

std::string Runtime::build_options(const std::string& extra) const {
  std::string opts = "-cl-std=CL1.2";
  // Correctly rounded divide and sqrt: the kernels must give the host twin's bits (docs/design.md, "Determinism").
  if (info_.correctly_rounded_divide_sqrt) opts += " -cl-fp32-correctly-rounded-divide-sqrt";
  // Oclgrind 21.10 interprets LLVM 14 IR but lacks intrinsics that LLVM 14's inliner emits
  // (llvm.experimental.noalias.scope.decl when it inlines a function returning a struct): at -O2,
  // or with the encoders' forced inlining (cl/keys.h), it cannot create the kernels. Unoptimised,
  // un-inlined IR has none of them, and its diagnostics name source lines. The arithmetic is the
  // same (FP_CONTRACT OFF either way), so are the bits.
  if (info_.is_simulator()) opts += " -cl-opt-disable -DRS_NO_FORCED_INLINE";
  // A CPU runs a work-group's work-items one after another, so the trace kernels prefetch the ray
  // of the work-item RS_RAY_PREFETCH_DISTANCE places ahead (cl/trace.cl says why; a GPU hides the
  // load behind other warps). Oclgrind gets it too, to check the prefetch's index (it compiles no
  // prefetch instruction).
  if (info_.type == "CPU" || info_.is_simulator())
    opts += fmt::format(" -DRS_PREFETCH_AHEAD={}", RS_RAY_PREFETCH_DISTANCE);
  if (!extra.empty()) opts += " " + extra;
  // Options for every kernel build, e.g. -DRS_PORTABLE_MASK_BITS on an x86 OpenCL compiler that
  // lacks the target builtins cl/lanes.h uses there (docs/trace.md).
  if (const char* env = std::getenv("RAYSORT_CL_OPTIONS"); env && *env) opts += std::string(" ") + env;
  return opts;
}

cl::Program Runtime::build(const std::vector<std::string>& files, const std::string& extra_options) {
  std::string source;
  for (auto& f : files) source += kernel_source(f);
  std::string names;
  for (auto& f : files) names += (names.empty() ? "" : ", ") + f;
  return build_source(source, names, extra_options);
}

cl::Program Runtime::build_source(const std::string& source, const std::string& names, const std::string& extra_options) {
  std::string opts = build_options(extra_options);
  // One build per (options, source) and runtime: every scene's Tracer and DeviceEncoder, and every
  // test, asks for the same programs.
  std::string key = opts + '\n' + source;
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;
  auto t0 = std::chrono::steady_clock::now();
  cl::Program program;
  cl_call("creating program " + names, [&] { program = cl::Program(context_, source); });
  cl_int err = CL_SUCCESS;
  try {
    program.build(std::vector<cl::Device>{info_.device}, opts.c_str());
  } catch (const cl::BuildError& e) {
    err = e.err();
  } catch (const cl::Error& e) {
    err = e.err();
  }
  build_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (err != CL_SUCCESS) {
    std::string log;
    try {
      log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(info_.device);
    } catch (const cl::Error&) {
      log = "(no build log available)";
    }
    throw BuildError(fmt::format("OpenCL build of {} failed with {} on device '{}' ({})\n  options: {}\n  build log:\n{}\n"
                                 "  (RAYSORT_CL_OPTIONS adds build options; -DRS_PORTABLE_MASK_BITS avoids the x86 "
                                 "target builtins of cl/lanes.h)",
                                 names, cl_error_name(err), info_.name, info_.platform_name, opts, trim(log)),
                     err, trim(log));
  }
  programs_.emplace(std::move(key), program);
  return program;
}

void Runtime::zero(const std::string& name, const cl::Buffer& b, std::size_t bytes) {
  cl_call("clearing '" + name + "'", [&] {
    if (!info_.is_simulator()) {
      queue_.enqueueFillBuffer(b, cl_uchar(0), 0, bytes);
      return;
    }
    const std::vector<unsigned char> zeros(bytes, 0);
    queue_.enqueueWriteBuffer(b, CL_TRUE, 0, bytes, zeros.data());  // blocking: zeros is local
  });
}

namespace {
// Test hook (tests/cli_test.cpp): RAYSORT_TEST_MAX_ALLOC_BYTES=N[:NAME] lowers the device's
// maximum allocation to N bytes, for every buffer or only for buffers whose name contains NAME,
// so a test can force the "allocation larger than the device allows" path on any device.
std::uint64_t max_alloc_for(const std::string& name, std::uint64_t device_max) {
  const char* env = std::getenv("RAYSORT_TEST_MAX_ALLOC_BYTES");
  if (!env || !*env) return device_max;
  std::string spec = env;
  auto colon = spec.find(':');
  if (colon != std::string::npos && name.find(spec.substr(colon + 1)) == std::string::npos) return device_max;
  return std::min<std::uint64_t>(device_max, std::strtoull(spec.c_str(), nullptr, 10));
}
}  // namespace

cl::Buffer Runtime::buffer(const std::string& name, std::size_t bytes, cl_mem_flags flags, const void* host_data) {
  std::string doing = fmt::format("allocating '{}' ({}) on {}", name, human_bytes(bytes), info_.name);
  const std::uint64_t max_alloc = max_alloc_for(name, info_.max_alloc_bytes);
  if (bytes > max_alloc)
    throw ClError(fmt::format("{}: larger than the device's maximum allocation of {}; use a smaller resolution or batch",
                              doing, human_bytes(max_alloc)),
                  CL_INVALID_BUFFER_SIZE);
  return cl_call(doing, [&] { return cl::Buffer(context_, flags, bytes, const_cast<void*>(host_data)); });
}

KernelProvenance kernel_provenance() {
  KernelProvenance k;
  k.source = kernel_dir().empty() ? "embedded" : kernel_dir();
  if (const char* env = std::getenv("RAYSORT_CL_OPTIONS")) k.cl_options = env;
  // The embedded list names every kernel file; with --kernels each is read from the folder instead.
  std::uint64_t h = kFnv1aOffsetBasis;
  auto mix = [&h](std::string_view bytes) {
    h = fnv1a("\xff", fnv1a(bytes, h));  // a separator byte, so "ab" + "c" differs from "a" + "bc"
  };
  for (const EmbeddedFile& f : embedded_files()) {
    if (f.path.rfind("cl/", 0) != 0) continue;
    mix(f.path);
    mix(read_kernel_file(std::string(f.path)));
  }
  k.hash = fmt::format("{:016x}", h);
  return k;
}

}  // namespace raysort
