#pragma once
// The per-thread scratch space behind IntegratorWorkspace (integrator.h): reused between
// observers, so that the hot loop does not allocate once it has grown to the largest
// observer's needs.

#include <memory>
#include <vector>

#include "facets/detail/surface_cache.h"
#include "facets/patch.h"
#include "facets/vec3.h"

namespace glint::detail {

struct Workspace {
  std::vector<Vec3> observer_local_m;  // the observer in each object's frame
  std::vector<SubFacet> stack;         // the uniform twin's traversal
  SurfaceCache surfaces;               // the lobe scheme's geometry, kept between observers

  // The scheme's own state of type T (the refinement's pieces and queues, the lobe scheme's
  // node pool), made at its first use and kept, with its capacity, for the next observers.
  // Looked up once per observer, so a scheme needs no member here.
  template <class T>
  T& kept() {
    for (const std::unique_ptr<Held>& held : kept_) {
      if (auto* of_type = dynamic_cast<HeldOf<T>*>(held.get())) return of_type->value;
    }
    auto made = std::make_unique<HeldOf<T>>();
    T& value = made->value;
    kept_.push_back(std::move(made));
    return value;
  }

 private:
  struct Held {
    virtual ~Held() = default;
  };
  template <class T>
  struct HeldOf final : Held {
    T value;
  };
  std::vector<std::unique_ptr<Held>> kept_;
};

}  // namespace glint::detail
