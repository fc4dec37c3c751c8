// An exclusive prefix sum of P.n unsigned integers (lgh_gpu::scan): the population counts
// of the input words where P.popcount is 1. Integer sums are exact, so the result does not
// depend on the order of anything.

struct ScanParams {
    n: u32,
    popcount: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> P: ScanParams;
