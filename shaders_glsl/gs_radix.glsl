// Device-wide LSD radix sort of (key, value) uint pairs, 8-bit digits
// (splatedit/render/gaussian/gpu_sort.py): per pass an upsweep (per-block digit
// histograms), a scan (per digit over the blocks, reduce-then-scan: one
// workgroup per digit) and a stable scatter (local ranks in the block).
// The element count is read on the GPU (gs_radix_setup.comp writes it and the
// indirect dispatch size into `args`): the CPU never reads it back.
// The layout of set 0 is RADIX_SET in gpu_sort.py; the push constants RADIX_PUSH
// in splatedit/render/uniforms.py.

const uint RADIX = 256u;             // digit values (8 bits); = the workgroup size
const uint ITEMS = 8u;               // keys per invocation per block
const uint BLOCK = RADIX * ITEMS;    // keys per workgroup (RADIX_BLOCK in gpu_sort.py)

layout(std430, set = 0, binding = 0) readonly buffer RCount { uint count_words[]; };
layout(std430, set = 0, binding = 1) readonly buffer RKeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = 2) readonly buffer RValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = 3) writeonly buffer RKeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = 4) writeonly buffer RValsOut { uint vals_out[]; };
// [0, RADIX): keys per digit of the pass; then RADIX rows (digit-major) of one
// count per block, scanned in place to the block's offset inside the digit
layout(std430, set = 0, binding = 5) buffer RHist { uint hist[]; };
// x, y, z: the dispatch of one workgroup per block; w: the element count n
layout(std430, set = 0, binding = 6) buffer RArgs { uint args[4]; };

layout(push_constant) uniform RadixPush {
    uint shift;          // bit of the pass's digit (0, 8, 16, 24)
    uint count_index;    // the count's uint index in count_words
    uint capacity;       // elements the buffers hold (the count is clamped to it)
    uint pad;
} RP;

uint radix_blocks(uint n) { return (n + BLOCK - 1u) / BLOCK; }
