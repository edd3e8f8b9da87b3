// Radix sort, one pass: the stable scatter of one block.  The block is read
// in ITEMS rounds of 256 consecutive keys; in a round, slot s holds key
// block start + round * 256 + s.  Slots form groups (subgroups, or
// GROUP_SIZE-slot groups in the shared-memory variant): the rank of a key
// among the equal digits of its group before it, then per digit an exclusive
// prefix over the groups (one invocation per digit), then the scatter to
// digit base + block offset + keys of the digit in earlier rounds + that.
// Equal digits keep their input order: the sort is stable.
// Defines before the include: SUBGROUP (ballot variant) or GROUP_SIZE.

layout(local_size_x = 256) in;
const uint MAX_GROUPS = 32u;                 // subgroups of >= 8 invocations
// counts (then exclusive prefixes) per group and digit, two groups per word (16 bits each)
shared uint s_cnt[(MAX_GROUPS / 2u) * RADIX];
shared uint s_base[RADIX];   // destination of the digit's first key of this round
shared uint s_tot[RADIX];    // keys of the digit in this round
shared uint s_scan[RADIX];
#ifndef SUBGROUP
shared uint s_dig[RADIX];    // digit per slot (RADIX: no key)
#endif

void main() {
    uint t = gl_LocalInvocationIndex;
    uint b = gl_WorkGroupID.x;
    uint n = args[3];
    uint nb = radix_blocks(n);
#ifdef SUBGROUP
    uint slot = gl_SubgroupID * gl_SubgroupSize + gl_SubgroupInvocationID;
    uint g = gl_SubgroupID, groups = gl_NumSubgroups;
#else
    uint slot = t;
    uint g = t / GROUP_SIZE, groups = RADIX / GROUP_SIZE;
#endif
    // digit bases: exclusive scan of the digit totals
    uint tot = hist[t];
    s_scan[t] = tot;
    barrier();
    for (uint o = 1u; o < RADIX; o <<= 1u) {
        uint add = t >= o ? s_scan[t - o] : 0u;
        barrier();
        s_scan[t] += add;
        barrier();
    }
    s_base[t] = s_scan[t] - tot + hist[RADIX + t * nb + b];
    s_tot[t] = 0u;
    for (uint r = 0u; r < ITEMS; ++r) {
        // P1 (invocation t = digit t): advance the base past the last round, clear the counts
        s_base[t] += s_tot[t];
        for (uint w = 0u; w < MAX_GROUPS / 2u; ++w) s_cnt[w * RADIX + t] = 0u;
        uint i = b * BLOCK + r * RADIX + slot;
        bool valid = i < n;
        uint key = valid ? keys_in[i] : 0u;
        uint dig = (key >> RP.shift) & 0xFFu;
#ifndef SUBGROUP
        s_dig[slot] = valid ? dig : RADIX;
#endif
        barrier();
        // P2: rank inside the group, the group's count by its first key of the digit
        uint rank = 0u, count = 0u;
#ifdef SUBGROUP
        uvec4 same = subgroupBallot(valid);
        for (uint k = 0u; k < 8u; ++k) {
            uvec4 bit = subgroupBallot(((dig >> k) & 1u) != 0u);
            same &= ((dig >> k) & 1u) != 0u ? bit : ~bit;
        }
        rank = subgroupBallotExclusiveBitCount(same);
        count = subgroupBallotBitCount(same);
#else
        uint g0 = g * GROUP_SIZE;
        if (valid) {
            for (uint j = g0; j < slot; ++j) rank += s_dig[j] == dig ? 1u : 0u;
            if (rank == 0u)
                for (uint j = slot; j < g0 + GROUP_SIZE; ++j) count += s_dig[j] == dig ? 1u : 0u;
        }
#endif
        if (valid && rank == 0u) atomicOr(s_cnt[(g >> 1u) * RADIX + dig], count << (16u * (g & 1u)));
        barrier();
        // P3 (invocation t = digit t): exclusive prefix of the digit's counts over the groups
        uint run = 0u;
        for (uint q = 0u; q < groups; ++q) {
            uint wi = (q >> 1u) * RADIX + t, sh = 16u * (q & 1u);
            uint word = s_cnt[wi];
            uint c = (word >> sh) & 0xFFFFu;
            s_cnt[wi] = (word & ~(0xFFFFu << sh)) | (run << sh);
            run += c;
        }
        s_tot[t] = run;
        barrier();
        // P4: scatter
        if (valid) {
            uint dst = s_base[dig] + ((s_cnt[(g >> 1u) * RADIX + dig] >> (16u * (g & 1u))) & 0xFFFFu) + rank;
            keys_out[dst] = key;
            vals_out[dst] = vals_in[i];
        }
        barrier();
    }
}
