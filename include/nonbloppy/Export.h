// SPDX-License-Identifier: Apache-2.0
/// @file Export.h
/// @brief NONBLOPPY_API, the mark on every public non-inline function and class.
///
/// The library is compiled with hidden symbol visibility (-fvisibility=hidden
/// -fvisibility-inlines-hidden), so the shared library exports only what carries this
/// mark: the nonbloppy:: public API, nothing of OpenVDB's templates or of the internals.
/// The static library is built from the same objects; the mark is harmless there.
/// (OpenVDB's own templates keep default visibility inside the library, see
/// src/VisibilityPrelude.h; the shared library's version script then exports nonbloppy::
/// symbols only.)

#ifndef NONBLOPPY_EXPORT_H
#define NONBLOPPY_EXPORT_H

#if defined(_WIN32)
// Windows DLLs are not supported yet: the library is used statically there.
#  define NONBLOPPY_API
#elif defined(__GNUC__) || defined(__clang__)
#  define NONBLOPPY_API __attribute__((visibility("default")))
#else
#  define NONBLOPPY_API
#endif

#endif // NONBLOPPY_EXPORT_H
