"""The figures gallery page lists every figure and table of the folder."""

from snapmorph.figures_gallery import write_gallery


def test_gallery_lists_everything_in_paper_order(tmp_path):
    for name in ("zz_extra.png", "arrays_M.png", "specimens_forcedef.png", "design_maps.png"):
        (tmp_path / name).write_bytes(b"\x89PNG")
    (tmp_path / "specimens_table.md").write_text("| a |")
    index = write_gallery(tmp_path)
    text = index.read_text()
    assert index.name == "index.md"
    order = [text.index(f"![{s}]({s}.png)") for s in
             ("specimens_forcedef", "design_maps", "arrays_M", "zz_extra")]
    assert order == sorted(order)
    assert "[specimens_table](specimens_table.md)" in text
    assert "b = 0" in text  # the maps' b is stated
    write_gallery(tmp_path)  # a second run does not list index.md itself
    assert "(index.md)" not in (tmp_path / "index.md").read_text()
