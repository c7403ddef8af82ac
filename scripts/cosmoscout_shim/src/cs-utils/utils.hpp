// Stand-in for CosmoScout VR's src/cs-utils/utils.hpp (commit
// e59005a3bbea2426c841f30da6cb35a4d313455e), for building its bruneton-preprocessor without
// cs-utils' library (which needs its generated export header and links curl, spdlog, ...).
// The preprocessor uses only cs::utils::toString (Preprocessor.cpp writes its GLSL constants with
// it); this gives the same function: the generic template streams the value with the default
// precision, the float and double specialisations use max_digits10, a string is quoted.
// Part of dustoptics' scripts/cosmoscout_preprocessor.py; MIT, as the CosmoScout file it mirrors.

#ifndef CS_UTILS_UTILS_HPP
#define CS_UTILS_UTILS_HPP

#include <limits>
#include <sstream>
#include <string>

namespace cs::utils {

template <typename T>
std::string toString(T const& v) {
  std::ostringstream oss;
  oss << v;
  return oss.str();
}

template <>
std::string toString(float const& v);

template <>
std::string toString(double const& v);

template <>
std::string toString(std::string const& v);

std::string toString(char const* v);

/// As cs::utils::replaceString: replaces every occurrence of sFind in sInput by sReplace.
void replaceString(std::string& sInput, std::string const& sFind, std::string const& sReplace);

} // namespace cs::utils

#endif // CS_UTILS_UTILS_HPP
