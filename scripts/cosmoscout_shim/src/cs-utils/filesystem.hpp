// Stand-in for CosmoScout VR's src/cs-utils/filesystem.hpp (commit
// e59005a3bbea2426c841f30da6cb35a4d313455e), for building its bruneton-preprocessor without
// cs-utils' library. The preprocessor uses loadToString (its shaders, read relative to the working
// directory: CosmoScout's root) and createDirectoryRecursively (its output directory); these have
// the same signatures and behaviour (filesystem.cpp). One addition: main.cpp (at this commit)
// passes boost::filesystem::system_complete(output) to createDirectoryRecursively, whose parameter
// is a std::filesystem::path; Debian 12's Boost 1.74 path does not convert to it implicitly, so an
// overload taking the Boost path forwards its string (the same directory is created).
// Part of dustoptics' scripts/cosmoscout_preprocessor.py; MIT, as the CosmoScout file it mirrors.

#ifndef CS_UTILS_FILESYSTEM_HPP
#define CS_UTILS_FILESYSTEM_HPP

#include <boost/filesystem/path.hpp>
#include <filesystem>
#include <string>

namespace cs::utils::filesystem {

/// Creates all required directories for @param path if they do not exist.
void createDirectoryRecursively(std::filesystem::path const& path,
    std::filesystem::perms permissions = std::filesystem::perms::owner_all |
                                         std::filesystem::perms::group_read |
                                         std::filesystem::perms::others_read);

/// The overload for main.cpp's Boost path (see the header comment).
inline void createDirectoryRecursively(boost::filesystem::path const& path) {
  createDirectoryRecursively(std::filesystem::path(path.string()));
}

/// Returns the contents of the file as a string. Any occurrences of \r\n will be replaced by \n.
std::string loadToString(std::string const& file);

} // namespace cs::utils::filesystem

#endif // CS_UTILS_FILESYSTEM_HPP
