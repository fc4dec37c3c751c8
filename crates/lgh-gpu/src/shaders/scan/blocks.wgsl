// The second step of the prefix sum: one workgroup scans the P.n block totals in place
// (exclusive) and writes the grand total.

@group(0) @binding(1) var<storage, read_write> blocks: array<u32>;
@group(0) @binding(2) var<storage, read_write> total: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_id) lid: vec3<u32>) {
    var carry = 0u;
    let chunks = (P.n + 255u) / 256u;
    for (var c = 0u; c < chunks; c++) {
        let i = c * 256u + lid.x;
        var x = 0u;
        if (i < P.n) {
            x = blocks[i];
        }
        part[lid.x] = x;
        workgroupBarrier();
        scan_part(lid.x);
        if (i < P.n) {
            blocks[i] = carry + part[lid.x] - x;
        }
        carry += part[255];
        workgroupBarrier();
    }
    if (lid.x == 0u) {
        total[0] = carry;
    }
}
