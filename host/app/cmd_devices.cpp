// raysort devices: every OpenCL platform/device with the limits that shape the kernels.
#include <fmt/format.h>

#include "app/commands.h"
#include "runtime/runtime.h"
#include "trace/tracer.h"

namespace raysort {

void register_devices_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("devices", "list OpenCL platforms and devices");
  cmd->callback([] {
    // With no device, select_device throws the one message that says what to install.
    auto def = select_device("");
    auto devices = list_devices();
    for (auto& d : devices) {
      fmt::print("[{}] {}{}\n", d.index, d.name, d.index == def.index ? "   (default)" : "");
      fmt::print("    platform        {} ({})\n", d.platform_name, d.platform_version);
      fmt::print("    type            {}{}\n", d.type,
                 d.is_simulator()           ? "   (simulator: checks every access, for correctness only, never the default)"
                 : d.is_single_threaded()   ? "   (single-threaded: one core, never the default)"
                                            : "");
      fmt::print("    OpenCL          {} / {}\n", d.version, d.opencl_c_version);
      fmt::print("    driver          {}\n", d.driver_version);
      fmt::print("    compute units   {}\n", d.compute_units);
      fmt::print("    global memory   {}\n", human_bytes(d.global_mem_bytes));
      fmt::print("    local memory    {}\n", human_bytes(d.local_mem_bytes));
      fmt::print("    max allocation  {}\n", human_bytes(d.max_alloc_bytes));
      fmt::print("    max work-group  {}\n", d.max_work_group_size);
      fmt::print("    float vector    preferred {}, native {} (trace --layout packet: packets of {} rays)\n",
                 d.preferred_float_width, d.native_float_width,
                 packet_width(resolve_trace_layout(TraceLayout::Packet, d)));
    }
  });
}

}  // namespace raysort
