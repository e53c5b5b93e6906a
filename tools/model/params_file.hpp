#pragma once
// --params-file: the YAML hystloop-identify --out writes, read back as parameter assignments.
// The top-level key is the model name, below it the parameter names, nested maps flattened with
// dots and lists joined with commas, so each entry goes through the same table and the same
// strict parsing as --param:
//
//   mem: {c1: 5e-9, c2: 1.7e-12, c3: 1.2}                 -> c1=5e-9, c2=1.7e-12, c3=1.2
//   banning: {hysteresis: {a: 8.58e-9, ...}, stage: {...}} -> hysteresis.a=8.58e-9, ...
//   pi: {count: 3, thresholds: [0, 80, 160], weights: [...]} -> count=3, thresholds=0,80,160, ...
//
// Other top-level sections are left alone (the file may be a whole hystloop config).

#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "models/param_table.hpp"

namespace hystloop::model_tool {

class ParamsFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ParamsFile {
  std::string model;                    // the section used
  std::vector<Assignment> assignments;  // origin "<path>: <model>.<key>"
};

// `model` is the --model given, or "" to take the file's only model section. Throws
// ParamsFileError naming the file (and the key) when the file cannot be read, is not YAML, has
// no such section, or holds something that is neither a value nor a list of values.
ParamsFile read_params_file(const std::string& path, std::string_view model);

}  // namespace hystloop::model_tool
