// Stand-in for the part of CosmoScout VR's src/cs-utils/filesystem.cpp (commit
// e59005a3bbea2426c841f30da6cb35a4d313455e) that the bruneton-preprocessor uses, same behaviour
// (see filesystem.hpp for why a stand-in).

#include "filesystem.hpp"

#include "utils.hpp"

#include <fstream>
#include <iterator>

namespace cs::utils::filesystem {

void createDirectoryRecursively(
    std::filesystem::path const& path, std::filesystem::perms permissions) {
  if (!std::filesystem::exists(path.parent_path())) {
    createDirectoryRecursively(path.parent_path(), permissions);
  }
  std::filesystem::create_directory(path);
  std::filesystem::permissions(path, permissions);
}

std::string loadToString(std::string const& file) {
  std::ifstream f(file);
  std::string   content;

  f.seekg(0, std::ios::end);
  content.reserve(f.tellg());
  f.seekg(0, std::ios::beg);

  content.assign((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  replaceString(content, "\r\n", "\n");

  return content;
}

} // namespace cs::utils::filesystem
