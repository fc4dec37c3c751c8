// The first step of an exclusive prefix sum (integers: exact, whatever the order): each
// workgroup scans 1024 elements (the population counts of words with P.popcount) and
// writes its total to `blocks`.

@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> dst: array<u32>;
@group(0) @binding(3) var<storage, read_write> blocks: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>) {
    let base = wid.x * 1024u + lid.x * 4u;
    var before: array<u32, 4>;
    var sum = 0u;
    for (var j = 0u; j < 4u; j++) {
        var x = 0u;
        if (base + j < P.n) {
            x = src[base + j];
            if (P.popcount == 1u) {
                x = countOneBits(x);
            }
        }
        before[j] = sum;
        sum += x;
    }
    part[lid.x] = sum;
    workgroupBarrier();
    scan_part(lid.x);
    let start = part[lid.x] - sum;
    for (var j = 0u; j < 4u; j++) {
        if (base + j < P.n) {
            dst[base + j] = start + before[j];
        }
    }
    if (lid.x == 255u) {
        blocks[wid.x] = part[255];
    }
}
