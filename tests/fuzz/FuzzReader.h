// SPDX-License-Identifier: Apache-2.0
/// @file FuzzReader.h
/// @brief The body shared by the libFuzzer targets: run one reader on the bytes and accept
///        only nonbloppy::Error (the readers' way of saying "bad file"). Anything else —
///        a crash, a sanitizer report, another exception, a hang — is a bug to fix.

#ifndef NONBLOPPY_FUZZ_READER_H
#define NONBLOPPY_FUZZ_READER_H

#include <nonbloppy/Error.h>

#include <cstddef>
#include <cstdint>

#define NONBLOPPY_FUZZ_READER(call)                                                       \
    extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size)              \
    {                                                                                     \
        const char* data = reinterpret_cast<const char*>(bytes);                          \
        (void)data;                                                                       \
        try {                                                                             \
            call;                                                                         \
        } catch (const nonbloppy::Error&) {                                               \
        }                                                                                 \
        return 0;                                                                         \
    }

#endif // NONBLOPPY_FUZZ_READER_H
