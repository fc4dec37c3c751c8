// Sorts every list's lights into ascending order (the CPU's, where the write kernel's slots
// are the scheduler's), one workgroup a list: a bitonic sort in workgroup memory for lists
// of up to SHARED lights, in the lists buffer itself for longer ones. Ascending order is
// unique, so the lists do not depend on the scheduling.

@group(0) @binding(0) var<uniform> P: BinParams;
@group(0) @binding(1) var<storage, read_write> lists: array<u32>;

const SHARED: u32 = 2048u;
const THREADS: u32 = 256u;

var<workgroup> keys: array<u32, SHARED>;
var<workgroup> list_start: u32;
var<workgroup> list_len: u32;

// The power of two at or above m.
fn pow2_at_least(m: u32) -> u32 {
    return 1u << (32u - countLeadingZeros(max(m, 2u) - 1u));
}

// Sorts the `len` keys of workgroup memory (padded with the largest u32 to m, a power of
// two): every merge of a bitonic sort in both directions.
fn sort_shared(lid: u32, m: u32) {
    for (var k = 2u; k <= m; k <<= 1u) {
        for (var j = k >> 1u; j > 0u; j >>= 1u) {
            for (var t = lid; t < m / 2u; t += THREADS) {
                let i = 2u * j * (t / j) + t % j;
                let a = keys[i];
                let b = keys[i + j];
                if ((a > b) == ((i & k) == 0u)) {
                    keys[i] = b;
                    keys[i + j] = a;
                }
            }
            workgroupBarrier();
        }
    }
}

// Sorts `len` lights of the lists buffer from `base` in place: a bitonic sort whose merges
// all ascend (the first step of each compares mirrored pairs), so that the missing keys of
// the padding to m, the largest, never move and their pairs can be skipped.
fn sort_global(lid: u32, base: u32, len: u32, m: u32) {
    for (var k = 2u; k <= m; k <<= 1u) {
        for (var j = k >> 1u; j > 0u; j >>= 1u) {
            for (var t = lid; t < m / 2u; t += THREADS) {
                var i: u32;
                var p: u32;
                if (j == k >> 1u) {
                    let block = t / j;
                    let off = t % j;
                    i = block * k + off;
                    p = block * k + k - 1u - off;
                } else {
                    i = 2u * j * (t / j) + t % j;
                    p = i + j;
                }
                if (p < len) {
                    let a = lists[base + i];
                    let b = lists[base + p];
                    if (a > b) {
                        lists[base + i] = b;
                        lists[base + p] = a;
                    }
                }
            }
            storageBarrier();
        }
    }
}

@compute @workgroup_size(256)
fn main(@builtin(local_invocation_id) lid3: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>,
        @builtin(num_workgroups) nw: vec3<u32>) {
    let lid = lid3.x;
    for (var l = wid.x; l < P.lists; l += nw.x) {
        if (lid == 0u) {
            list_start = lists[l];
            list_len = lists[l + 1u] - lists[l];
        }
        let start = workgroupUniformLoad(&list_start);
        let len = workgroupUniformLoad(&list_len);
        let base = P.lights_base + start;
        let m = pow2_at_least(len);
        if (len > 1u && len <= SHARED) {
            for (var i = lid; i < m; i += THREADS) {
                keys[i] = select(0xffffffffu, lists[base + i], i < len);
            }
            workgroupBarrier();
            sort_shared(lid, m);
            for (var i = lid; i < len; i += THREADS) {
                lists[base + i] = keys[i];
            }
        } else if (len > SHARED) {
            sort_global(lid, base, len, m);
        }
        workgroupBarrier();
    }
}
