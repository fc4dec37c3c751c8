// Finding a marked vertex among all (the kernels that declare `bits` and `prefix`).

const NONE: u32 = 0xffffffffu;

// The number of vertex `key` of the bit set starting at word `word0`, NONE if unmarked: the
// marked vertices before its word (the scan) and before it in its word.
fn find(key: u32, word0: u32) -> u32 {
    let w = word0 + (key >> 5u);
    let b = key & 31u;
    let m = bits[w];
    if (((m >> b) & 1u) == 0u) {
        return NONE;
    }
    return prefix[w] + countOneBits(m & ((1u << b) - 1u));
}
