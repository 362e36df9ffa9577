from snapmorph.cli import main

raise SystemExit(main())
