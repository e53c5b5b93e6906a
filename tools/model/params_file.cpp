#include "params_file.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>

#include "model_registry.hpp"

namespace hystloop::model_tool {
namespace {

void flatten(const YAML::Node& node, const std::string& key, const std::string& path, const std::string& model,
             std::vector<Assignment>& out) {
  const std::string origin = path + ": " + model + "." + key;
  switch (node.Type()) {
    case YAML::NodeType::Scalar: out.push_back({key, node.Scalar(), origin}); return;
    case YAML::NodeType::Sequence: {
      std::string joined;
      for (std::size_t i = 0; i < node.size(); ++i) {
        if (!node[i].IsScalar())
          throw ParamsFileError(origin + ": list entry " + std::to_string(i) + " is not a value");
        if (i > 0) joined += ',';
        joined += node[i].Scalar();
      }
      out.push_back({key, joined, origin});
      return;
    }
    case YAML::NodeType::Map:
      for (const auto& kv : node) {
        const std::string sub = kv.first.as<std::string>();
        flatten(kv.second, key.empty() ? sub : std::string(key).append(".").append(sub), path, model, out);
      }
      return;
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined: throw ParamsFileError(origin + ": no value");
  }
}

}  // namespace

ParamsFile read_params_file(const std::string& path, std::string_view model) {
  std::ifstream in(path);
  if (!in) throw ParamsFileError(path + ": cannot open the parameters file");
  YAML::Node doc;
  try {
    doc = YAML::Load(in);
  } catch (const YAML::Exception& e) {
    throw ParamsFileError(path + ":" + std::to_string(e.mark.line + 1) + ": not valid YAML: " + e.msg);
  }
  if (!doc.IsMap()) {
    throw ParamsFileError(path + ": expected a map with the model name at the top (e.g. 'mem: {c1: 5e-9, ...}')");
  }
  std::vector<std::string> sections;  // top-level keys that name a model
  for (const auto& kv : doc) {
    const std::string key = kv.first.as<std::string>();
    if (find_model(key) != nullptr) sections.push_back(key);
  }
  std::string found;
  for (const auto& s : sections) found += (found.empty() ? "" : ", ") + s;
  ParamsFile result;
  if (model.empty()) {
    if (sections.size() != 1) {
      throw ParamsFileError(path + ": " +
                            (sections.empty() ? "no model section (expected one of " + model_names() + ")"
                                              : "several model sections (" + found + "): choose one with --model"));
    }
    result.model = sections.front();
  } else {
    result.model = std::string(model);
    if (!doc[result.model]) {
      throw ParamsFileError(path + ": no '" + result.model + "' section" +
                            (found.empty() ? std::string() : " (it has: " + found + ")"));
    }
  }
  const YAML::Node section = doc[result.model];
  if (!section.IsMap()) {
    throw ParamsFileError(path + ": " + result.model + ": expected a map of parameter names to values");
  }
  flatten(section, "", path, result.model, result.assignments);
  return result;
}

}  // namespace hystloop::model_tool
