#include "app/commands.h"
namespace raysort {
void register_render_command(CLI::App&) {}
}  // namespace raysort
