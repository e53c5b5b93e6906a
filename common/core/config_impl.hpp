#pragma once
// Private to config.cpp / config_keys.cpp: the yaml-cpp tree behind Config.

#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>
#include <vector>

#include "core/config.hpp"

namespace hystloop {

struct Config::Impl {
  YAML::Node root{YAML::NodeType::Map};
  std::string source = "<empty>";
  // Keys set over the base file, in order, each with where it came from: "--set" (apply_override)
  // or a layered file's name (layer).
  std::vector<std::pair<std::string, std::string>> overridden;

  // Where `path`'s value came from: the last override or layer that set it (or a parent of it),
  // else the base file.
  const std::string& source_for(std::string_view path) const;
};

// "a.b.c" -> {"a", "b", "c"}; empty parts are left in for the caller to refuse.
std::vector<std::string> split_config_path(std::string_view path);

}  // namespace hystloop
