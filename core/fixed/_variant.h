/* One SIMD variant of the filter: the generated lane functions and four block drivers.
 *
 * Included by _filter_<variant>.c after it chose the instruction set (a target pragma) and
 * defined VARIANT; defines classify{3,4}_{f64,f32}_<VARIANT> (rule ids, -1 undecided).
 */
#include "_kernels.h"

#define CHUNK 64  /* pairs per block: the stage buffers stay in the L1 cache */
#define LANES 8   /* pairs between two rounds of prefetching the next block */
#define GLUE_(a, b) a##_##b
#define GLUE(a, b) GLUE_(a, b)

#define N 3
#define T double
#define FIRST first3_f64
#define FULL full3_f64
#define SECOND second3
#define THIRD third3_f64
#define CLASSIFY GLUE(classify3_f64, VARIANT)
#include "_blocks.h"
#undef T
#undef FIRST
#undef FULL
#undef THIRD
#undef CLASSIFY
#define T float
#define FIRST first3_f32
#define FULL full3_f32
#define THIRD third3_f32
#define CLASSIFY GLUE(classify3_f32, VARIANT)
#include "_blocks.h"
#undef N
#undef T
#undef FIRST
#undef FULL
#undef SECOND
#undef THIRD
#undef CLASSIFY

#define N 4
#define T double
#define FIRST first4_f64
#define FULL full4_f64
#define SECOND second4
#define THIRD third4_f64
#define CLASSIFY GLUE(classify4_f64, VARIANT)
#include "_blocks.h"
#undef T
#undef FIRST
#undef FULL
#undef THIRD
#undef CLASSIFY
#define T float
#define FIRST first4_f32
#define FULL full4_f32
#define THIRD third4_f32
#define CLASSIFY GLUE(classify4_f32, VARIANT)
#include "_blocks.h"
#undef N
#undef T
#undef FIRST
#undef FULL
#undef SECOND
#undef THIRD
#undef CLASSIFY
