// The marked vertices of each resolution in use, into misc[1 + k].

@group(0) @binding(1) var<storage, read> word_start: array<u32>;
@group(0) @binding(2) var<storage, read> prefix: array<u32>;
@group(0) @binding(3) var<storage, read> total: array<u32>;
@group(0) @binding(4) var<storage, read_write> misc: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if (k >= P.count) {
        return;
    }
    var end = total[0];
    if (k + 1u < P.count) {
        end = prefix[word_start[k + 1u]];
    }
    misc[1u + k] = end - prefix[word_start[k]];
}
