#pragma once
#include "sand/material.hpp"
#include "terrain/vertex_box.hpp"

namespace ps::sand {

// Told by sand tools which heights they changed and in what material, so that settling can
// start there (Settler implements it).
class EditListener {
 public:
  virtual ~EditListener() = default;
  virtual void edited(const terrain::VertexBox& region, const Material& material) = 0;
};

}  // namespace ps::sand
