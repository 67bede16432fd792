// tinyobjloader compiled into the fuzz build (instead of Debian's prebuilt library), so the
// sanitizers and the fuzzer's coverage see inside it.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
