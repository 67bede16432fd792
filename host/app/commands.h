#pragma once
// Subcommands of the raysort CLI. Each registers itself on the app and runs from its callback;
// a callback that finds a failure sets the exit code through set_command_exit_code.
#include <CLI/CLI.hpp>

namespace raysort {

void register_commands(CLI::App& app);
void register_devices_command(CLI::App& app);
void register_scenes_command(CLI::App& app);
void register_trace_command(CLI::App& app);
void register_sortbench_command(CLI::App& app);
void register_sortcheck_command(CLI::App& app);
void register_render_command(CLI::App& app);
void register_encode_command(CLI::App& app);
void register_run_command(CLI::App& app);
void register_compare_command(CLI::App& app);
void register_merge_command(CLI::App& app);
void register_report_command(CLI::App& app);
void register_sweep_command(CLI::App& app);
void register_rays_command(CLI::App& app);

// The exit codes of every command (docs/errors.md, "Exit codes"): one scheme for the parser's
// errors, the commands' refusals and their findings.
inline constexpr int kExitOk = 0;
inline constexpr int kExitBadInput = 1;     // bad input or a failed check: the message says what to change
inline constexpr int kExitDoesNotFit = 2;   // the request does not fit this machine (ResourceError, bad_alloc)
inline constexpr int kExitInternal = 3;     // a bug: please report it
inline constexpr int kExitInterrupted = 130;  // `run` stopped by SIGINT (130) or SIGTERM (143) at its next arm; rerun to resume

void set_command_exit_code(int code);
int command_exit_code();

}  // namespace raysort
