// raysort — command-line entry point. Each subcommand lives in its own file in host/app/.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdio>

#include "app/commands.h"
#include "render/frame_memory.h"
#include "runtime/runtime.h"

int main(int argc, char** argv) {
  CLI::App app{"raysort: ray reordering benchmark suite (encode -> radix sort -> trace) on OpenCL"};
  app.require_subcommand(1);
  app.set_version_flag("--version", RAYSORT_VERSION);
  std::string kernels;
  app.add_option("--kernels", kernels, "read OpenCL kernels from this cl/ folder instead of the embedded copies");
  app.parse_complete_callback([&] {
    if (!kernels.empty()) raysort::set_kernel_dir(kernels);
  });
  raysort::register_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const raysort::ResourceError& e) {  // does not fit this machine (render/frame_memory.h)
    std::fprintf(stderr, "raysort: error: %s\n", e.what());
    return 2;
  } catch (const raysort::Error& e) {
    std::fprintf(stderr, "raysort: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {  // past the estimate of render/frame_memory.h: a safety net
    std::fprintf(stderr, "raysort: error: out of host memory; lower --resolution or --spp\n");
    return 2;
  } catch (const std::exception& e) {  // a bug: please report it
    std::fprintf(stderr, "raysort: internal error: %s\n", e.what());
    return 3;
  }
  return raysort::command_exit_code();
}
