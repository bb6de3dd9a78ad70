from subenv.cli import main
import sys
sys.exit(main())
