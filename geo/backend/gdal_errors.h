#pragma once
/// @file
/// @brief GDAL's drivers registered once (and kept off the network: keepGdalOffline()), and its
/// messages kept from the terminal while a GdalErrors lives: what failed is said once, in glint's
/// own message, with GDAL's reason.

#include <string>

namespace glint::detail {

/// @brief Leaves GDAL no way to open a connection: every file system of its but the local
/// ones (memory, archives) opens nothing, every HTTP request fails, PROJ's network is off and
/// the database drivers are gone. Called once, with the drivers' registration.
void keepGdalOffline();

class GdalErrors {
 public:
  GdalErrors();
  ~GdalErrors();
  GdalErrors(const GdalErrors&) = delete;
  GdalErrors& operator=(const GdalErrors&) = delete;

  /// @brief @p what, and GDAL's last message after ": " where it gave one.
  [[nodiscard]] static std::string explain(const std::string& what);
};

}  // namespace glint::detail
