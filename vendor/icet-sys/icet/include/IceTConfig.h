/* -*- c -*- *******************************************************/
/*
 * Copyright (C) 2003 Sandia Corporation
 * Under the terms of Contract DE-AC04-94AL85000 with Sandia Corporation,
 * the U.S. Government retains certain rights in this software.
 *
 * This source code is released under the New BSD License.
 */

/*
 * volcast: written by hand from upstream's src/include/IceTConfig.h.in
 * (IceT commit abf5bf2b92c0531170c8db2621b375065c7da7c4), with every
 * @VARIABLE@ and #cmakedefine resolved the way upstream's CMake would resolve
 * them for a default static build on LP64 Linux (x86_64 or aarch64).
 * build.rs refuses any other target (pointer width other than 64, Windows).
 * See vendor/icet-sys/VOLCAST.md.
 */

#ifndef __IceTConfig_h
#define __IceTConfig_h

/* BUILD_SHARED_LIBS defaults to OFF upstream, and the cc crate builds a
 * static archive:  #cmakedefine ICET_BUILD_SHARED_LIBS  ->  undefined. */
/* #undef ICET_BUILD_SHARED_LIBS */

#ifdef _WIN32
#include <windows.h>
#endif

#if defined(_WIN32) && defined(ICET_BUILD_SHARED_LIBS)
#  ifdef IceTCore_EXPORTS
#    define ICET_EXPORT __declspec( dllexport )
#    define ICET_STRATEGY_EXPORT __declspec( dllexport )
#  else
#    define ICET_EXPORT __declspec( dllimport )
#    define ICET_STRATEGY_EXPORT __declspec( dllimport )
#  endif
#  ifdef IceTGL_EXPORTS
#    define ICET_GL_EXPORT __declspec( dllexport )
#  else
#    define ICET_GL_EXPORT __declspec( dllimport )
#  endif
#  ifdef IceTGL3_EXPORTS
#    define ICET_GL3_EXPORT __declspec( dllexport )
#  else
#    define ICET_GL3_EXPORT __declspec( dllimport )
#  endif
#  ifdef IceTMPI_EXPORTS
#    define ICET_MPI_EXPORT __declspec( dllexport )
#  else
#    define ICET_MPI_EXPORT __declspec( dllimport )
#  endif
#else /* _WIN32 && SHARED_LIBS */
#  define ICET_EXPORT
#  define ICET_GL_EXPORT
#  define ICET_GL3_EXPORT
#  define ICET_STRATEGY_EXPORT
#  define ICET_MPI_EXPORT
#endif /* _WIN32 && SHARED_LIBS */

/* From the top-level CMakeLists.txt at the vendored commit. */
#define ICET_MAJOR_VERSION      2
#define ICET_MINOR_VERSION      2
#define ICET_PATCH_VERSION      0
#define ICET_VERSION            "2.2.0"

/* CHECK_TYPE_SIZE results on LP64 Linux (x86_64, aarch64). __int64 is an
 * MSVC type that GCC and Clang do not define, so CMake leaves it undefined. */
#define ICET_SIZEOF_CHAR           1
#define ICET_SIZEOF_SHORT          2
#define ICET_SIZEOF_INT            4
#define ICET_SIZEOF_LONG           8
#define ICET_SIZEOF_LONG_LONG      8
/* #undef ICET_SIZEOF___INT64 */
#define ICET_SIZEOF_FLOAT          4
#define ICET_SIZEOF_DOUBLE         8
#define ICET_SIZEOF_VOID_P         8

#if ICET_SIZEOF_CHAR == 1
typedef char IceTInt8;
typedef unsigned char IceTUnsignedInt8;
#else
#error "No valid data type for 8 bit integers found."
#endif

#if ICET_SIZEOF_SHORT == 2
typedef short IceTInt16;
typedef unsigned short IceTUnsignedInt16;
#else
#error "No valid data type for 16 bit integers founds."
#endif

#if ICET_SIZEOF_INT == 4
typedef int IceTInt32;
typedef unsigned int IceTUnsignedInt32;
#elif ICET_SIZEOF_LONG == 4
typedef long IceTInt32;
typedef unsigned long IceTUnsignedInt32;
#elif ICET_SIZEOF_SHORT == 4
typedef short IceTInt32;
typedef unsigned short IceTUnsignedInt32;
#else
#error "No valid data type for 32 bit integers found."
#endif

#if ICET_SIZEOF_INT == 8
typedef int IceTInt64;
typedef unsigned int IceTUnsignedInt64;
#elif ICET_SIZEOF_LONG == 8
typedef long IceTInt64;
typedef unsigned long IceTUnsignedInt64;
#elif defined(ICET_SIZEOF_LONG_LONG) && (ICET_SIZEOF_LONG_LONG == 8)
typedef long long IceTInt64;
typedef unsigned long long IceTUnsignedInt64;
#elif defined(ICET_SIZEOF___INT64) && (ICET_SIZEOF___INT64 == 8)
typedef __int64 IceTInt64;
typedef unsigned __int64 IceTUnsignedInt64;
#else
#error "No valid data type for 64 bit integers found."
#endif

#if ICET_SIZEOF_FLOAT == 4
typedef float IceTFloat32;
#else
#error "No valid data type for 32 bit floating point found."
#endif

#if ICET_SIZEOF_DOUBLE == 8
typedef double IceTFloat64;
#else
#error "No valid data type for 64 bit floating point found."
#endif

#if ICET_SIZEOF_VOID_P == 4
typedef IceTInt32 IceTPointerArithmetic;
#elif ICET_SIZEOF_VOID_P == 8
typedef IceTInt64 IceTPointerArithmetic;
#else
#error "Unexpected pointer size."
#endif

/* Upstream's defaults: ICET_MAGIC_K is 8 (16 only when CMAKE_SYSTEM_NAME is
 * BlueGene) and ICET_MAX_IMAGE_SPLIT is 500000; both can be overridden at
 * configure time by the ICET_MAGIC_K / ICET_MAX_IMAGE_SPLIT environment
 * variables, which this hand-written header does not read. */
#define ICET_MAGIC_K_DEFAULT            8
#define ICET_MAX_IMAGE_SPLIT_DEFAULT    500000

/* ICET_USE_MPE (MPE tracing of MPI calls) is an advanced option, OFF by
 * default:  #cmakedefine ICET_USE_MPE  ->  undefined. */
/* #undef ICET_USE_MPE */

/* ICET_USE_PARICOMPRESS (CUDA image compression for the OpenGL 3 layer,
 * which is not vendored) is OFF by default  ->  undefined. */
/* #undef ICET_USE_PARICOMPRESS */

#endif /*__IceTConfig_h*/
