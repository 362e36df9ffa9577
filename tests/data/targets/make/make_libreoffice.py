"""LibreOffice Calc part: flat-ODS spreadsheets written here, converted to CSV by soffice itself.
    python3 make/make_libreoffice.py OUTDIR BUILDDIR      (needs soffice: libreoffice-calc-nogui)
"""
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import geom as G  # noqa: E402
from make_csv import pts_of, read_exp  # noqa: E402

FODS = """<?xml version="1.0" encoding="UTF-8"?>
<office:document xmlns:office="urn:oasis:names:tc:opendocument:xmlns:office:1.0"
 xmlns:table="urn:oasis:names:tc:opendocument:xmlns:table:1.0" xmlns:text="urn:oasis:names:tc:opendocument:xmlns:text:1.0"
 xmlns:style="urn:oasis:names:tc:opendocument:xmlns:style:1.0" xmlns:number="urn:oasis:names:tc:opendocument:xmlns:datastyle:1.0"
 xmlns:fo="urn:oasis:names:tc:opendocument:xmlns:xsl-fo-compatible:1.0"
 office:version="1.3" office:mimetype="application/vnd.oasis.opendocument.spreadsheet">
<office:automatic-styles>
 <number:number-style style:name="N1" number:language="{lang}" number:country="{country}">
  <number:number number:decimal-places="3" number:min-decimal-places="3" number:min-integer-digits="1"/>
 </number:number-style>
 <style:style style:name="ce1" style:family="table-cell" style:data-style-name="N1"/>
</office:automatic-styles>
<office:body><office:spreadsheet><table:table table:name="target">
{rows}
</table:table></office:spreadsheet></office:body></office:document>
"""


def fods(header, pts, lang, country):
    rows = ["<table:table-row>" + "".join(f'<table:table-cell office:value-type="string"><text:p>{h}</text:p>'
                                          f'</table:table-cell>' for h in header) + "</table:table-row>"]
    for x, y in pts:
        rows.append("<table:table-row>" + "".join(
            f'<table:table-cell table:style-name="ce1" office:value-type="float" office:value="{v:.6f}">'
            f'<text:p>{v:.3f}</text:p></table:table-cell>' for v in (x, y)) + "</table:table-row>")
    return FODS.format(rows="\n".join(rows), lang=lang, country=country)


def soffice(src, outdir, filt):
    subprocess.run(["soffice", "--headless", "--norestore", "--convert-to", filt, "--outdir", str(outdir), str(src)],
                   check=True, capture_output=True, timeout=180)


def main(outdir, build):
    outdir, build = Path(outdir).resolve(), Path(build).resolve()
    work = build / "lo"
    work.mkdir(parents=True, exist_ok=True)
    man = []
    ver = subprocess.run(["soffice", "--version"], capture_output=True, text=True).stdout.split()
    program = "LibreOffice Calc " + (ver[1] if len(ver) > 1 else "")
    p = pts_of("s2arc", 2.0)
    # 1. plain CSV export (en-US): comma separated, 3 decimals as formatted
    (work / "lo_s2arc_mm.fods").write_text(fods(["x_mm", "y_mm"], p, "en", "US"))
    soffice(work / "lo_s2arc_mm.fods", work, "csv:Text - txt - csv (StarCalc):44,34,76,1")
    shutil.copy(work / "lo_s2arc_mm.csv", outdir / "csv" / "libreoffice_s2arc_mm.csv")
    q = [[round(x, 3), round(y, 3)] for x, y in p]
    man.append(dict(file="csv/libreoffice_s2arc_mm.csv", program=program,
                    what="LibreOffice Calc 'Save as CSV' of a sheet (header x_mm,y_mm, 3 decimals shown): S curve",
                    **read_exp(G.np.array(q) if hasattr(G, "np") else __import__("numpy").array(q),
                               note="values as displayed (3 decimals)")))
    # 2. German locale: semicolon separator, decimal comma
    (work / "lo_hook_de.fods").write_text(fods(["x_mm", "y_mm"], pts_of("hook", 2.0), "de", "DE"))
    soffice(work / "lo_hook_de.fods", work, "csv:Text - txt - csv (StarCalc):59,34,76,1,,1031,false,true,true")
    shutil.copy(work / "lo_hook_de.csv", outdir / "csv" / "libreoffice_hook_de_semicolon.csv")
    q = [[round(x, 3), round(y, 3)] for x, y in pts_of("hook", 2.0)]
    e = read_exp(__import__("numpy").array(q), note="German-locale export: ';' separates fields, ',' is the decimal "
                 "mark. Read it, or refuse with a message that names the format (reason_alt)")
    man.append(dict(file="csv/libreoffice_hook_de_semicolon.csv", program=program,
                    what="LibreOffice Calc CSV export in German locale (field separator ';', decimal comma): hook",
                    reason_alt=["unsupported-format"], **e))
    (build / "manifest_libreoffice.json").write_text(json.dumps(man, indent=1))
    print(len(man), "LibreOffice entries;", (outdir / "csv" / "libreoffice_hook_de_semicolon.csv").read_text()[:60])


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
