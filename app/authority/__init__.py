"""One authority: the station's command layer, its one role policy, its users.

Everything outside reaches it through this face (`from app.authority import ...`).
"""

from app.authority.layer import APPLIED, Answer, Commands, Reason, Ticket, Who, write_range
from app.authority.policy import (
    ADMIN,
    ENGINEER,
    OPERATOR,
    POLICY,
    ROLES,
    VIEWER,
    Action,
    Refusal,
    Source,
    needs,
    policy_table,
    rank,
)

__all__ = ["ADMIN", "APPLIED", "ENGINEER", "OPERATOR", "POLICY", "ROLES", "VIEWER", "Action", "Answer",
           "Commands", "Reason", "Refusal", "Source", "Ticket", "Who", "needs", "policy_table", "rank",
           "write_range"]
