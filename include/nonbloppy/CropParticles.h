// SPDX-License-Identifier: Apache-2.0
/// @file CropParticles.h
/// @brief Stage "crop particles": keep the particles inside a box, with their attributes,
///        before anything is meshed.
///
/// Simulations leave particles where the surface is not wanted: the domain's walls and
/// floor (a tank's boundary particles, an emitter), or a region outside the shot. Cropping
/// before meshing also makes the spacing estimate and the density grid see only what is kept.
/// The surface near the box's faces is that of the kept particles: it closes around them, not
/// cut open along the faces, and reaches at most r_e (the kernel's reach) past the box.

#ifndef NONBLOPPY_CROP_PARTICLES_H
#define NONBLOPPY_CROP_PARTICLES_H

#include <nonbloppy/Export.h>
#include <nonbloppy/Particles.h>

#include <openvdb/Types.h>

namespace nonbloppy {

/// The particles of @a particles whose positions lie inside @a box, its faces included
/// (min <= p <= max on every axis; a NaN position lies in no box), in their order, each
/// attribute cut the same way, and its `skipped` list kept.
/// Cost: two parallel passes over the positions and one copy of what is kept; deterministic.
/// Thread-safety: reentrant.
/// @throw ParameterError("particle box: its minimum x 2 exceeds its maximum 1") where a
///        minimum exceeds its maximum, "particle box: its minimum y is nan, not a finite
///        number" for a NaN or infinite bound (an unbounded side takes a huge finite one),
///        and, as writeParticles(), ParameterError("attribute 'id' does not hold one value
///        per particle") for an attribute whose bytes are not one value per particle (or
///        "attribute 'id' has 0 components, at least 1 needed").
NONBLOPPY_API ParticleSet cropParticles(const ParticleSet& particles, const openvdb::BBoxd& box);

/// Throw the ParameterError cropParticles() would for @a box, and nothing else: the check
/// of a box given before any particles are read.
NONBLOPPY_API void checkParticleBox(const openvdb::BBoxd& box);

} // namespace nonbloppy

#endif // NONBLOPPY_CROP_PARTICLES_H
