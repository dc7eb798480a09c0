// Tag registry: the name of each sensor tag by number.
//
// Defaults to thesis Table 5.2 (1 Forehead, 2 Chest, ..., 15 Right foot). A JSON file
// {"1": "Forehead", "2": "Chest", ...} replaces or extends it.
#pragma once

#include <map>
#include <string>

#include "metro/core/status.hpp"

namespace metro {

class TagRegistry {
 public:
  // Thesis Table 5.2.
  static TagRegistry Default();
  // Default() overlaid with the entries of a JSON object file.
  static Result<TagRegistry> Load(const std::string& path);

  // The tag's name, or "tag N" when the registry has none.
  std::string Name(int sensor) const;

 private:
  std::map<int, std::string> names_;
};

}  // namespace metro
