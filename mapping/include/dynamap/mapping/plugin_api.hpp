#pragma once

// Include this in a backend plugin's .cpp and write DYNAMAP_DEFINE_BACKEND(MyBackend): the plugin
// is then a shared library named libdynamap_backend_<name>.so exporting one extern "C" factory.

#include "dynamap/mapping/map_backend.hpp"

#define DYNAMAP_DEFINE_BACKEND(BackendClass)                               \
  extern "C" __attribute__((visibility("default"))) ::dynamap::MapBackend* \
  dynamap_create_backend_v6(const ::dynamap::BackendParams& params) {      \
    return new BackendClass(params);                                       \
  }
