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

// The workgroup's 256 partial sums, scanned in place (inclusive) by `scan_part`.
var<workgroup> part: array<u32, 256>;

// Hillis-Steele over `part`; every invocation of the workgroup calls it (barriers).
fn scan_part(i: u32) {
    for (var off = 1u; off < 256u; off <<= 1u) {
        var t = 0u;
        if (i >= off) {
            t = part[i - off];
        }
        workgroupBarrier();
        part[i] += t;
        workgroupBarrier();
    }
}
