#pragma once
#include "terrain/mesh.hpp"
#include "terrain/terrain.hpp"

namespace ps::terrain {

// View-independent mesh of the whole planet: a triangle splits while its split vertex's error
// bound exceeds maxErrorMetres. Crack-free for the same reason as the view-dependent mesh (the
// errors are nested), and the true 3D deviation of every full-resolution vertex from the mesh
// is at most maxErrorMetres. Positions are relative to the planet's centre (Mesh::eye = 0).
// Throws core::InputError for a negative or non-finite maxErrorMetres.
Mesh meshToError(const Terrain& terrain, double maxErrorMetres);

}  // namespace ps::terrain
