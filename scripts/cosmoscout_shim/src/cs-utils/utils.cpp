// Stand-in for the part of CosmoScout VR's src/cs-utils/utils.cpp (commit
// e59005a3bbea2426c841f30da6cb35a4d313455e) that the bruneton-preprocessor uses: toString's
// specialisations and replaceString, copied in behaviour (see utils.hpp for why a stand-in).

#include "utils.hpp"

namespace cs::utils {

void replaceString(std::string& sInput, std::string const& sFind, std::string const& sReplace) {
  size_t iPos = 0;
  while ((iPos = sInput.find(sFind, iPos)) != std::string::npos) {
    sInput.replace(iPos, sFind.length(), sReplace);
    iPos += sReplace.length();
  }
}

template <>
std::string toString(float const& v) {
  std::ostringstream oss;
  oss.precision(std::numeric_limits<float>::max_digits10);
  oss << v;
  return oss.str();
}

template <>
std::string toString(double const& v) {
  std::ostringstream oss;
  oss.precision(std::numeric_limits<double>::max_digits10);
  oss << v;
  return oss.str();
}

template <>
std::string toString(std::string const& v) {
  std::string tmp(v);
  replaceString(tmp, "\"", "\\\"");
  replaceString(tmp, "\n", "\\n");
  return "\"" + tmp + "\"";
}

std::string toString(char const* v) {
  return toString(std::string(v));
}

} // namespace cs::utils
