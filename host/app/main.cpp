// raysort — command-line entry point. Each subcommand lives in its own file in host/app/.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cstdio>
#include <string>
#include <vector>

#include "app/commands.h"
#include "render/frame_memory.h"
#include "runtime/runtime.h"
#include "util/build_commit.h"

namespace {

std::vector<std::string> command_names(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) names.push_back(sub->get_name());
  return names;
}

// The first word that is not an option (or --kernels' value) names the command. CLI11 says only
// "A subcommand is required" for a word it does not know; this names the word and the commands.
void check_command_word(CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--kernels") {
      ++i;
      continue;
    }
    if (!arg.empty() && arg[0] == '-') continue;
    const std::vector<std::string> names = command_names(app);
    for (const auto& n : names)
      if (n == arg) return;
    throw raysort::Error(fmt::format("unknown command '{}'; the commands are: {}; see `raysort --help`", arg,
                                     fmt::join(names, ", ")));
  }
}

// CLI11's message for a parse error, on one line, with the usage hint of the command it was parsing.
std::string parse_error_message(CLI::App& app, const CLI::ParseError& e) {
  std::string what = e.what();
  while (!what.empty() && (what.back() == '\n' || what.back() == '.')) what.pop_back();
  for (char& c : what)
    if (c == '\n') c = ' ';
  std::string command;
  for (const CLI::App* sub : app.get_subcommands()) command = sub->get_name();
  if (command.empty() && e.get_name() == "RequiredError" && what == "A subcommand is required")
    what = fmt::format("no command given; the commands are: {}", fmt::join(command_names(app), ", "));
  return fmt::format("{}; see `raysort {}--help`", what, command.empty() ? "" : command + " ");
}

}  // namespace

// Exit codes: one scheme for every error (app/commands.h, docs/errors.md "Exit codes").
int main(int argc, char** argv) {
  using namespace raysort;
  CLI::App app{"raysort: ray reordering benchmark suite (encode -> radix sort -> trace) on OpenCL"};
  app.require_subcommand(1);
  app.set_version_flag("--version", fmt::format("{} (commit {})", RAYSORT_VERSION, build_commit()));
  std::string kernels;
  app.add_option("--kernels", kernels, "read OpenCL kernels from this cl/ folder instead of the embedded copies");
  bool parsed = false;  // past the command line: from here on a std::logic_error is a bug of ours
  app.parse_complete_callback([&] {
    parsed = true;
    if (!kernels.empty()) set_kernel_dir(kernels);
  });
  register_commands(app);
  app.footer("Exit status: 0 ok; 1 bad input or a failed check; 2 the request does not fit this machine; 3 an "
             "internal error (a bug); 130 or 143 a run interrupted by SIGINT or SIGTERM, resumable (docs/errors.md)");
  try {
    check_command_word(app, argc, argv);
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);  // --help, --version
    std::fprintf(stderr, "raysort: error: %s\n", parse_error_message(app, e).c_str());
    return kExitBadInput;
  } catch (const ResourceError& e) {  // does not fit this machine (render/frame_memory.h)
    std::fprintf(stderr, "raysort: error: %s\n", e.what());
    return kExitDoesNotFit;
  } catch (const Error& e) {
    std::fprintf(stderr, "raysort: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::logic_error& e) {
    // CLI11 converts a flag's value with std::stoll and lets its out_of_range escape
    // (`--no-large=99999999999999999999`, found by fuzz/cli_fuzzer.cpp): bad input, not a bug.
    if (parsed) {
      std::fprintf(stderr, "raysort: internal error: %s\n", e.what());
      return kExitInternal;
    }
    std::fprintf(stderr, "raysort: error: a value on the command line is out of range or malformed (%s); see `raysort "
                 "--help`\n", e.what());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {  // past the estimate of render/frame_memory.h: a safety net
    std::fprintf(stderr, "raysort: error: out of host memory; lower --resolution or --spp\n");
    return kExitDoesNotFit;
  } catch (const std::exception& e) {  // a bug: please report it
    std::fprintf(stderr, "raysort: internal error: %s\n", e.what());
    return kExitInternal;
  }
  return command_exit_code();
}
