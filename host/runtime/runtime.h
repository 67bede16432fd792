#pragma once
// OpenCL runtime: device listing and choice, program build from the embedded kernels, buffers
// with named allocations, profiling-event timing, and errors that say what was being done.
#include <CL/opencl.hpp>

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "util/error.h"

namespace raysort {

// An OpenCL error: the call that failed, the error code's name, and what raysort was doing.
class ClError : public Error {
 public:
  ClError(std::string what, cl_int code) : Error(std::move(what)), code_(code) {}
  cl_int code() const { return code_; }

 private:
  cl_int code_;
};

// A program that did not build (Runtime::build_source): the message holds the build log, the
// options and the device; log() is the compiler's log alone, for a caller that reports it against
// a file of its own (an encoder from a file, encode/encoder_file.h).
class BuildError : public ClError {
 public:
  BuildError(std::string what, cl_int code, std::string log) : ClError(std::move(what), code), log_(std::move(log)) {}
  const std::string& log() const { return log_; }

 private:
  std::string log_;
};

// "CL_OUT_OF_RESOURCES" for -5, and so on; "CL_UNKNOWN_ERROR(<n>)" otherwise.
std::string cl_error_name(cl_int code);

// Runs f(); an OpenCL failure inside becomes a ClError naming `doing` and the device.
template <class F>
auto cl_call(std::string_view doing, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const cl::Error& e) {
    throw ClError(std::string(e.what()) + " failed with " + cl_error_name(e.err()) + " while " + std::string(doing),
                  e.err());
  }
}

struct DeviceInfo {
  int index = -1;  // position in list_devices(), stable for a machine
  cl::Platform platform;
  cl::Device device;
  std::string platform_name;
  std::string platform_version;
  std::string name;
  std::string type;  // "GPU", "CPU", "ACCELERATOR", "OTHER"
  std::string version;
  std::string driver_version;
  std::string opencl_c_version;
  std::uint32_t compute_units = 0;
  std::uint64_t global_mem_bytes = 0;
  std::uint64_t local_mem_bytes = 0;
  std::uint64_t max_alloc_bytes = 0;
  std::size_t max_work_group_size = 0;
  bool correctly_rounded_divide_sqrt = false;
  // CL_DEVICE_PREFERRED_VECTOR_WIDTH_FLOAT / NATIVE_VECTOR_WIDTH_FLOAT: floats per vector register as
  // the driver sees it (16 on PoCL with AVX-512, 8 with AVX, 4 with SSE, 1 on NVIDIA GPUs). The
  // packet trace class takes its default width from the preferred one (trace/tracer.h).
  std::uint32_t preferred_float_width = 0;
  std::uint32_t native_float_width = 0;
  bool is_pocl() const { return platform_name.find("Portable Computing Language") != std::string::npos; }
  // Oclgrind: an interpreter that checks every memory access, for correctness, never for speed.
  // Its device type includes GPU and CPU, so it must be kept out of the default choice by name.
  bool is_simulator() const { return platform_name.find("Oclgrind") != std::string::npos; }
  // PoCL's `basic` device runs one work-item at a time on one core (its `pthread` device uses all).
  bool is_single_threaded() const { return is_simulator() || (is_pocl() && name.rfind("basic", 0) == 0); }
  // Real hardware at full speed: what the default and the "gpu" / "cpu" specs choose first.
  bool is_preferred() const { return !is_single_threaded(); }
  // A short name for result folders: "pocl-cpu-amd-epyc-...".
  std::string slug() const;
};

// Every device of every platform, in platform order. Empty when no ICD is installed.
std::vector<DeviceInfo> list_devices();

// The device named by spec: an index, "cpu", "gpu", or a case-insensitive substring of the device
// or platform name ("oclgrind", "basic", "pthread"). An empty spec reads RAYSORT_DEVICE, and without
// it picks the first GPU, else the first CPU, skipping simulators (Oclgrind) and single-threaded
// devices (PoCL basic) while any other device exists; "gpu" and "cpu" skip them the same way.
// Throws an Error listing the devices when nothing matches.
DeviceInfo select_device(std::string spec);

// Reads kernels from DIR instead of the embedded copies (kernel development: --kernels DIR).
void set_kernel_dir(std::string dir);

// What the kernels are built from, for a result set's meta.json ("kernels"): a run resumes, and
// compare reads two sets as one build, only when these agree.
struct KernelProvenance {
  std::string source;      // "embedded", or the --kernels folder
  std::string hash;        // FNV-1a 64 (hex) over every cl/ file's path and text as this binary reads them
  std::string cl_options;  // RAYSORT_CL_OPTIONS ("" when unset)
};
KernelProvenance kernel_provenance();

// The source of a kernel file ("cl/trace.cl") with its #include "x.h" lines replaced by the
// contents of cl/x.h, so programs build from one string with no include path.
std::string kernel_source(const std::string& path);

// Milliseconds between an event's start and end (profiling queue required).
double event_ms(const cl::Event& e);
// Milliseconds from the start of `first` to the end of `last`.
double event_span_ms(const cl::Event& first, const cl::Event& last);

std::string human_bytes(std::uint64_t bytes);

class Runtime {
 public:
  explicit Runtime(DeviceInfo info);

  const DeviceInfo& info() const { return info_; }
  cl::Context& context() { return context_; }
  cl::CommandQueue& queue() { return queue_; }

  // Builds a program from kernel files (e.g. {"cl/trace.cl"}) with the standard options
  // (OpenCL C 1.2, correctly rounded divide/sqrt where supported) plus `extra_options`.
  // On failure throws a BuildError holding the full build log, the options and the device.
  // A program already built with the same source and options is returned without rebuilding.
  cl::Program build(const std::vector<std::string>& files, const std::string& extra_options = "");
  // Builds a program from source text; `name` identifies it in errors.
  cl::Program build_source(const std::string& source, const std::string& name, const std::string& extra_options = "");
  // Total milliseconds spent in build() so far (reported apart from run times).
  double build_ms() const { return build_ms_; }
  std::string build_options(const std::string& extra) const;

  // A device buffer; the error for an allocation that fails names `name`, its size and the device.
  cl::Buffer buffer(const std::string& name, std::size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE,
                    const void* host_data = nullptr);

  // Sets the first `bytes` of b to zero (enqueued, not waited for). A fill, except on a simulator:
  // Oclgrind 21.10's uninitialised-value check does not see clEnqueueFillBuffer and would report
  // every later read, so there the zeros are written from the host.
  void zero(const std::string& name, const cl::Buffer& b, std::size_t bytes);

  template <class T, class Alloc>
  cl::Buffer upload(const std::string& name, const std::vector<T, Alloc>& v, cl_mem_flags flags = CL_MEM_READ_ONLY) {
    return buffer(name, std::max<std::size_t>(1, v.size()) * sizeof(T), flags | (v.empty() ? 0 : CL_MEM_COPY_HOST_PTR),
                  v.empty() ? nullptr : v.data());
  }
  template <class T>
  void download(const std::string& name, const cl::Buffer& b, std::vector<T>& out, std::size_t count) {
    out.resize(count);
    if (count == 0) return;
    cl_call("reading back '" + name + "'", [&] { queue_.enqueueReadBuffer(b, CL_TRUE, 0, count * sizeof(T), out.data()); });
  }

  // The global size for n work-items rounded up to a multiple of local (PoCL needs uniform groups).
  static std::size_t padded(std::size_t n, std::size_t local) { return (n + local - 1) / local * local; }

 private:
  DeviceInfo info_;
  cl::Context context_;
  cl::CommandQueue queue_;
  double build_ms_ = 0.0;
  std::map<std::string, cl::Program> programs_;  // built programs by options + source
};

}  // namespace raysort
