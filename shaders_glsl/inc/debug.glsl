// Debug printf for per-pixel traces. TRACEn(fmt, ...) prints only in the debug kernel
// (render_debug.comp) and only for the traced pixel and sample; elsewhere it compiles to
// nothing. (glslang has no variadic macros, hence one macro per argument count.)
#ifndef INC_DEBUG_GLSL
#define INC_DEBUG_GLSL

#include "common.glsl"

bool g_trace = false;  // set by raygen for the traced pixel and sample

#ifdef LANTERNA_DEBUG_PRINTF
#define TRACE0(f) if (g_trace) debugPrintfEXT(f)
#define TRACE1(f, a) if (g_trace) debugPrintfEXT(f, a)
#define TRACE2(f, a, b) if (g_trace) debugPrintfEXT(f, a, b)
#define TRACE3(f, a, b, c) if (g_trace) debugPrintfEXT(f, a, b, c)
#define TRACE4(f, a, b, c, d) if (g_trace) debugPrintfEXT(f, a, b, c, d)
#define TRACE5(f, a, b, c, d, e) if (g_trace) debugPrintfEXT(f, a, b, c, d, e)
#define TRACE6(f, a, b, c, d, e, g) if (g_trace) debugPrintfEXT(f, a, b, c, d, e, g)
#else
#define TRACE0(f)
#define TRACE1(f, a)
#define TRACE2(f, a, b)
#define TRACE3(f, a, b, c)
#define TRACE4(f, a, b, c, d)
#define TRACE5(f, a, b, c, d, e)
#define TRACE6(f, a, b, c, d, e, g)
#endif

#endif
