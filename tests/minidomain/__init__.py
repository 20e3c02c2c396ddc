"""A minimal second domain for the test suite: the same Panda, a table and a push button.

Not part of ``osg_control``: it is the example of ``docs/domains.md``, written the way a user
would write a domain in their own project. ``domain.py`` holds the data (nodes, facts,
skills, tasks, start regions) and the ``Domain`` factory; ``env.py`` the ``ArmEnv``
subclass; ``scene.xml`` the MJCF the Panda is attached to.
"""

from minidomain.domain import DOMAIN_NAME, mini_domain

__all__ = ["DOMAIN_NAME", "mini_domain"]
