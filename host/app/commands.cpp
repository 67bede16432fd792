#include "app/commands.h"

namespace raysort {

namespace {
int g_exit_code = 0;
}

void set_command_exit_code(int code) { g_exit_code = code; }
int command_exit_code() { return g_exit_code; }

void register_commands(CLI::App& app) {
  register_devices_command(app);
  register_scenes_command(app);
  register_trace_command(app);
  register_sortbench_command(app);
  register_sortcheck_command(app);
  register_render_command(app);
  register_encode_command(app);
  register_run_command(app);
  register_compare_command(app);
  register_merge_command(app);
  register_report_command(app);
  register_sweep_command(app);
  register_rays_command(app);
}

}  // namespace raysort
