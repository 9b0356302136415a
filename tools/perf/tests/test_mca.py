"""tools/perf/mca.py's loop extraction: the instructions between the llvm-mca markers in execution
order (GCC rotates loops, so the end marker can come first in the text). A pure function of the
assembly text; llvm-mca itself is not needed here."""

import pytest
from perf_support import load_tool


@pytest.fixture(scope="module")
def mca():
    return load_tool("mca.py")


# a rotated loop as GCC lays it out: the tail of the body (stores) first, then the begin marker,
# a uniform branch to a cold block (.L7: 3 instructions) and back, and a jump to the tail
ASM = """
kernel:
\tjmp\t.L9
.L6:
\tvmovups\t%zmm3, (%rsi)
#APP
\t# LLVM-MCA-END
#NO_APP
\taddq\t$16, %rcx
\tjle\t.L10
.L9:
#APP
\t# LLVM-MCA-BEGIN loop
#NO_APP
\tvmovups\t(%rdi), %zmm0
\ttestb\t%r9b, %r9b
\tjne\t.L7
\tvmulps\t%zmm0, %zmm0, %zmm1
.L8:
\tvaddps\t%zmm1, %zmm0, %zmm3
\tjmp\t.L6
.L7:
\tvaddps\t%zmm0, %zmm0, %zmm1
\tvmulps\t%zmm1, %zmm1, %zmm1
\tvsqrtps\t%zmm1, %zmm1
\tjmp\t.L8
.L10:
\tret
"""


def test_longest_path_through_rotated_loop(mca):
    body = mca.loop_body(ASM)
    # the cold block is the longer side of the uniform branch; the jumps themselves are dropped
    assert body == ["vmovups\t(%rdi), %zmm0", "testb\t%r9b, %r9b", "vaddps\t%zmm0, %zmm0, %zmm1",
                    "vmulps\t%zmm1, %zmm1, %zmm1", "vsqrtps\t%zmm1, %zmm1", "vaddps\t%zmm1, %zmm0, %zmm3",
                    "vmovups\t%zmm3, (%rsi)"]


def test_take_chooses_the_side(mca):
    fall = mca.loop_body(ASM, take=set())
    assert "vsqrtps\t%zmm1, %zmm1" not in fall and "vmulps\t%zmm0, %zmm0, %zmm1" in fall
    assert mca.loop_body(ASM, take={".L7"}) == mca.loop_body(ASM)


def test_loop_between_markers_is_an_error(mca):
    looping = ASM.replace("\tjmp\t.L6\n", "\tjmp\t.L9\n")  # back to the begin marker, never the end
    with pytest.raises(ValueError, match="loop"):
        mca.loop_body(looping)
    with pytest.raises(ValueError, match="loop"):   # with no conditional branch on the way
        mca.loop_body(looping, take=set())


def test_shortest_path_takes_the_cheap_side(mca):
    # the *_smooth keys: the fall-through side of the uniform branch (1 instruction, not 3)
    assert mca.loop_body(ASM, shortest=True) == mca.loop_body(ASM, take=set())
    assert len(mca.loop_body(ASM, shortest=True)) == len(mca.loop_body(ASM)) - 2


# llc's layout of a Dr.Jit kernel: set-up, the loop body from its label to the backward branch
LLC = """
drjit_1:
	movq	24(%rcx), %rax
	jmp	.LBB0_1
.LBB0_1:                                # %body
	vmovaps	(%rax,%rdi,4), %zmm0
	vdivps	%zmm1, %zmm0, %zmm0
	vmovntps	%zmm0, (%rdx,%rdi,4)
	addq	$16, %rdi
	cmpq	%rsi, %rdi
	jb	.LBB0_1
# %bb.2:
	vzeroupper
	retq
"""


def test_llc_loop_body(mca):
    assert mca.llc_loop_body(LLC) == ["vmovaps	(%rax,%rdi,4), %zmm0", "vdivps	%zmm1, %zmm0, %zmm0",
                                      "vmovntps	%zmm0, (%rdx,%rdi,4)", "addq	$16, %rdi", "cmpq	%rsi, %rdi",
                                      "jb	.LBB0_1"]
    with pytest.raises(ValueError, match="loop"):
        mca.llc_loop_body(LLC.replace("jb\t.LBB0_1", "jb\t.LBB0_3"))


def test_find_llvm_tool_skips_an_old_unversioned_tool(mca, monkeypatch, tmp_path):
    # Debian 12's unversioned llvm-mca is LLVM 14 (no -mcpu=znver4): not taken; a versioned one
    # of LLVM 17-19 is, and an unversioned one is when it is that new
    def fake_tool(path, major):
        path.write_text(f"#!/bin/sh\necho 'Debian LLVM version {major}.0.6'\n")
        path.chmod(0o755)
        return str(path)

    old = fake_tool(tmp_path / "llvm-mca", 14)
    found = {"llvm-mca": old}
    monkeypatch.setattr(mca.shutil, "which", lambda c: found.get(c))
    monkeypatch.setattr(mca, "Path", lambda c: tmp_path / "absent" / str(c).lstrip("/"))
    assert mca.llvm_major(old) == 14
    assert mca.find_llvm_tool("llvm-mca") is None
    found["llvm-mca"] = fake_tool(tmp_path / "llvm-mca-new", 19)
    assert mca.find_llvm_tool("llvm-mca") == found["llvm-mca"]
    found["llvm-mca-18"] = "/opt/llvm-mca-18"
    assert mca.find_llvm_tool("llvm-mca") == "/opt/llvm-mca-18"
