// SPDX-License-Identifier: Apache-2.0
/// @file Error.h
/// @brief The exceptions nonbloppy throws at its library boundary.
///
/// Every message is one line that names the file or parameter at fault and what was
/// required, e.g. "--blend must lie in [0,1], got 1.5" or
/// "truncated POINTS section (tests/data/x.vtk)". The command-line tool prints what()
/// as it is, so messages are written for a person reading a farm log.

#ifndef NONBLOPPY_ERROR_H
#define NONBLOPPY_ERROR_H

#include <nonbloppy/Export.h>

#include <stdexcept>
#include <string>

namespace nonbloppy {

/// Base of every exception nonbloppy throws on purpose.
class NONBLOPPY_API Error : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

/// A file could not be opened, read, parsed or written.
class NONBLOPPY_API FileError : public Error
{
public:
    using Error::Error;
};

/// A parameter lies outside its allowed range, or input data (e.g. NaN coordinates)
/// make the requested computation meaningless.
class NONBLOPPY_API ParameterError : public Error
{
public:
    using Error::Error;
};

/// The caller's interrupter asked to stop; no result was produced.
class NONBLOPPY_API CancelledError : public Error
{
public:
    using Error::Error;
};

} // namespace nonbloppy

#endif // NONBLOPPY_ERROR_H
