// Constructors of the concrete adapters, used only by the registry in adapter.cpp.
#pragma once

#include <memory>
#include <string_view>

#include "adapter.h"

namespace quadrant::scene {

/// `variant` is what follows "quadrant:" in the engine name ("" for the default).
std::unique_ptr<Adapter> MakeQuadrantAdapter(std::string_view variant);
std::unique_ptr<Adapter> MakeBox2dAdapter();
std::unique_ptr<Adapter> MakeBulletAdapter();
std::unique_ptr<Adapter> MakeChipmunkAdapter();

}  // namespace quadrant::scene
