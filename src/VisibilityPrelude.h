// SPDX-License-Identifier: Apache-2.0
/// @file VisibilityPrelude.h
/// @brief Private, force-included (-include) before every library source: declares OpenVDB's
///        templates with default visibility although the library builds with
///        -fvisibility=hidden.
///
/// Why: a template's instantiations take the visibility of its declaration. Declared hidden,
/// OpenVDB's Tree<…>::sTreeTypeName and friends would be hidden in our objects while their
/// guard variables stay STB_GNU_UNIQUE (global), so libopenvdb.so's own copies and ours get
/// mixed up and openvdb::initialize() dereferences a null type name (segfault, seen with
/// Debian's OpenVDB 10). Declaring them here, before any source includes them, keeps one
/// shared instance. Our own symbols stay hidden unless marked NONBLOPPY_API, and the
/// shared library's version script (cmake/nonbloppy.map) exports nonbloppy:: only.

#ifndef NONBLOPPY_VISIBILITY_PRELUDE_H
#define NONBLOPPY_VISIBILITY_PRELUDE_H

#pragma GCC visibility push(default)
#include <openvdb/openvdb.h>
#include <openvdb/tools/PointIndexGrid.h>
#pragma GCC visibility pop

#endif // NONBLOPPY_VISIBILITY_PRELUDE_H
