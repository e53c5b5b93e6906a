#pragma once
// Private to config.cpp / config_keys.cpp: the yaml-cpp tree behind Config.

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "core/config.hpp"

namespace hystloop {

struct Config::Impl {
  YAML::Node root{YAML::NodeType::Map};
  std::string source = "<empty>";
  std::vector<std::string> overridden;  // keys set by apply_override, in order

  // "--set" when `path` (or a parent of it) was overridden, else the file.
  const std::string& source_for(std::string_view path) const;
};

// "a.b.c" -> {"a", "b", "c"}; empty parts are left in for the caller to refuse.
std::vector<std::string> split_config_path(std::string_view path);

}  // namespace hystloop
