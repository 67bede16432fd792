#include "app/commands.h"
namespace raysort {
void register_scenes_command(CLI::App&) {}
}  // namespace raysort
