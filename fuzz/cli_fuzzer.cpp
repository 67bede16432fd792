// libFuzzer target for the command line (issue 44): random argv through the option parsing of every
// subcommand, the commands not run. The input is split at NUL bytes into arguments (at most 64).
// The app is built as main() builds it (register_commands); its parse-complete callback, which
// CLI11 runs after every option is checked and converted (the numeric ranges, --resolution, CLI11's
// own errors and requirements) and before any subcommand's callback, ends the parse, so nothing is
// loaded, allocated or measured. (Clearing the subcommands' callbacks instead would free the option
// storage their lambdas own: a use-after-free of the harness, not of raysort.) The app is built once
// and cleared between inputs (App::clear), as building it takes longer than a parse. A parse must return or throw a CLI11
// ParseError or raysort::Error; anything else (a crash, a sanitizer report, another exception) is a
// finding. Built by `make fuzz` (CMake option RAYSORT_FUZZ, clang).
#include <CLI/CLI.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/commands.h"
#include "util/error.h"

namespace {

struct ParseComplete {};

CLI::App& the_app() {
  static CLI::App* app = [] {
    auto* a = new CLI::App{"raysort"};
    a->require_subcommand(1);
    a->set_version_flag("--version", "fuzz");
    static std::string kernels;
    a->add_option("--kernels", kernels, "kernel folder");
    raysort::register_commands(*a);
    a->parse_complete_callback([] { throw ParseComplete{}; });
    return a;
  }();
  return *app;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> args{"raysort"};
  std::string current;
  for (std::size_t i = 0; i < size && args.size() < 64; ++i) {
    if (data[i] == 0) {
      args.push_back(current);
      current.clear();
    } else {
      current += static_cast<char>(data[i]);
    }
  }
  if (!current.empty() && args.size() < 64) args.push_back(current);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());

  CLI::App& app = the_app();
  app.clear();
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const ParseComplete&) {
  } catch (const CLI::ParseError&) {
  } catch (const raysort::Error&) {
  } catch (const std::logic_error&) {
    // CLI11's std::stoll on a flag's value (`--no-large=99999999999999999999`): main() reports it
    // as bad input, since it comes before the command line is parsed (host/app/main.cpp).
  }
  return 0;
}
