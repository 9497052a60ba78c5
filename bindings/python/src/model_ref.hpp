// The state behind an ngi.Model (shared by model.cpp and pipeline.cpp, which runs models on frames).
#pragma once
#include <string>

#include "common.hpp"
#include "ngi/model.hpp"

namespace ngi_py {

struct PyModel {
    DeviceRef device;
    ngi::Model model;
    std::string path;
    int sanitized = 0;                 // input values the last run() replaced
    ngi::DeviceBuffer input, output;   // run()'s device buffers, reused while the size stays
};

}  // namespace ngi_py
