// tinygltf's implementation, compiled once here with raysort's configuration (scene/tinygltf.h)
// rather than linking Debian's libtinygltf.so, which decodes every texture image through stb_image.
// Built without warnings (-w, CMakeLists.txt): the header is a third party's.
#define TINYGLTF_IMPLEMENTATION
#include "scene/tinygltf.h"
