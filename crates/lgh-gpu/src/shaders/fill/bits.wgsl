// The sub-image masks of cut recombination windows (fill/masks.wgsl): 64 bits as two words.

// Bit s of a 64-bit mask held as two words.
fn has_bit(m: vec2<u32>, s: u32) -> bool {
    let word = select(m.y >> ((s - 32u) & 31u), m.x >> (s & 31u), s < 32u);
    return (word & 1u) != 0u;
}
