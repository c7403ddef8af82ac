// Stand-in for CosmoScout VR's src/cs-core/Settings.hpp, for building its bruneton-preprocessor
// (plugins/csp-atmospheres/bruneton-preprocessor) without the rest of cs-core.
//
// What it replaces and why: the preprocessor's CMake target links all of cs-core (scene graph,
// GUI, SPICE, VR, ...), which cannot be built on a headless test machine, but its sources use
// only cs::core::Settings::serialize / deserialize (Params.cpp, Metadata.cpp), the
// cs::utils::DefaultProperty they read into (Params.hpp) and the adl_serializer for glm vectors
// (Metadata.cpp writes a glm::vec3). This header gives exactly those, with CosmoScout's semantics
// (read at commit e59005a3bbea2426c841f30da6cb35a4d313455e, src/cs-core/Settings.hpp and
// src/cs-utils/DefaultProperty.hpp / Property.hpp):
//   - deserialize(j, key, T&): mandatory, j.at(key) (throws when missing);
//   - deserialize(j, key, std::optional<T>&): std::nullopt when missing;
//   - deserialize(j, key, DefaultProperty<T>&): reset to its default when missing;
//   - serialize(j, key, T): always written; optional: only when set; DefaultProperty: only
//     when not at its default.
// Property<T> drops the change signal (nothing in the preprocessor connects to it) but keeps
// get/set, assignment from T, comparison and operator<< (which cs::utils::toString uses, so a
// DefaultProperty<bool> prints as 1/0 and a DefaultProperty<float> with the stream's default
// precision, as in CosmoScout). The other includes (boost filesystem, iostream, glm, json) are the
// ones the real header brings in transitively and the preprocessor's files rely on.
// Part of dustoptics' scripts/cosmoscout_preprocessor.py; MIT, as the CosmoScout file it mirrors.

#ifndef CS_CORE_SETTINGS_HPP
#define CS_CORE_SETTINGS_HPP

#include <boost/filesystem.hpp>
#include <cstdint>
#include <exception>
#include <glm/glm.hpp>
#include <glm/gtc/constants.hpp>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "../cs-utils/utils.hpp"

namespace cs::utils {

template <typename T>
class Property {
 public:
  Property() = default;
  explicit Property(T val)
      : mValue(std::move(val)) {
  }
  virtual ~Property() = default;

  virtual void set(T const& value) {
    mValue = value;
  }
  virtual T const& get() const {
    return mValue;
  }
  virtual Property<T>& operator=(T const& rhs) {
    set(rhs);
    return *this;
  }
  bool operator==(T const& rhs) const {
    return get() == rhs;
  }
  bool operator!=(T const& rhs) const {
    return get() != rhs;
  }
  T const& operator()() const {
    return get();
  }

 protected:
  T mValue{};
};

template <typename T>
std::ostream& operator<<(std::ostream& out_stream, Property<T> const& val) {
  out_stream << val.get();
  return out_stream;
}

template <typename T>
class DefaultProperty : public Property<T> {
 public:
  explicit DefaultProperty(T const& val)
      : Property<T>(val)
      , mDefaultValue(val) {
  }
  DefaultProperty(DefaultProperty<T> const& other)
      : Property<T>(other.mValue)
      , mDefaultValue(other.mDefaultValue) {
  }
  ~DefaultProperty() override = default;

  bool isDefault() const {
    return Property<T>::get() == mDefaultValue;
  }
  void reset() {
    Property<T>::set(mDefaultValue);
  }
  DefaultProperty<T>& operator=(DefaultProperty<T> const& rhs) {
    Property<T>::set(rhs.get());
    return *this;
  }
  DefaultProperty<T>& operator=(T const& rhs) override {
    Property<T>::set(rhs);
    return *this;
  }

 private:
  const T mDefaultValue;
};

} // namespace cs::utils

namespace nlohmann {

// As CosmoScout's Settings.hpp: glm vectors are JSON arrays.
template <int C, typename T, glm::qualifier Q>
struct adl_serializer<glm::vec<C, T, Q>> {
  static void to_json(json& j, glm::vec<C, T, Q> const& opt) {
    j = json::array();
    for (int i = 0; i < C; ++i) {
      j[i] = opt[i];
    }
  }
  static void from_json(json const& j, glm::vec<C, T, Q>& opt) {
    for (int i = 0; i < C; ++i) {
      j.at(i).get_to(opt[i]);
    }
  }
};

} // namespace nlohmann

namespace cs::core {

class Settings {
 public:
  /// As CosmoScout's Settings::DeserializationException: names the property that failed.
  class DeserializationException : public std::exception {
   public:
    DeserializationException(std::string property, std::string jsonError)
        : mProperty(std::move(property))
        , mJSONError(std::move(jsonError))
        , mMessage("Failed to parse settings for " + mProperty + ": " + mJSONError) {
    }
    char const* what() const noexcept override {
      return mMessage.c_str();
    }
    std::string const mProperty;
    std::string const mJSONError;
    std::string const mMessage;
  };

  template <typename T>
  static void deserialize(nlohmann::json const& j, std::string const& property, T& target) {
    naming(property, [&] { j.at(property).get_to(target); });
  }

  template <typename T>
  static void deserialize(
      nlohmann::json const& j, std::string const& property, std::optional<T>& target) {
    auto iter = j.find(property);
    if (iter == j.end()) {
      target = std::nullopt;
      return;
    }
    naming(property, [&] { target = iter->template get<T>(); });
  }

  template <typename T>
  static void deserialize(
      nlohmann::json const& j, std::string const& property, utils::DefaultProperty<T>& target) {
    auto iter = j.find(property);
    if (iter == j.end()) {
      target.reset();
      return;
    }
    naming(property, [&] { target = iter->template get<T>(); });
  }

  template <typename T>
  static void serialize(nlohmann::json& j, std::string const& property, T const& target) {
    j[property] = target;
  }

  template <typename T>
  static void serialize(
      nlohmann::json& j, std::string const& property, std::optional<T> const& target) {
    if (target) {
      j[property] = target.value();
    }
  }

  template <typename T>
  static void serialize(
      nlohmann::json& j, std::string const& property, utils::DefaultProperty<T> const& target) {
    if (!target.isDefault()) {
      j[property] = target.get();
    }
  }

 private:
  /// Runs read(), rethrowing what it throws as a DeserializationException that names the
  /// property, as each of CosmoScout's deserialize overloads does (an inner property's
  /// failure reads "'inner' in 'outer'").
  template <typename Read>
  static void naming(std::string const& property, Read&& read) {
    try {
      read();
    } catch (DeserializationException const& e) {
      throw DeserializationException(e.mProperty + " in '" + property + "'", e.mJSONError);
    } catch (std::exception const& e) {
      throw DeserializationException("'" + property + "'", e.what());
    }
  }
};

} // namespace cs::core

#endif // CS_CORE_SETTINGS_HPP
