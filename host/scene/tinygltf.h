#pragma once
// tinygltf (Debian libtinygltf-dev) as raysort uses it: no image decoding or writing (a ray batch
// needs no textures; images are counted as ignored), no external images read. Every file that
// includes tiny_gltf.h includes it through here, so all see the same configuration.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>
