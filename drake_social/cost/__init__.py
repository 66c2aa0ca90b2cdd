"""Social cost terms (pure numpy): Kirby's AGF, the multi-point sum, motion cost."""

from drake_social.cost.agf import PersonalSpace, agf, agf_algorithm1
from drake_social.cost.social import SocialCost

__all__ = ["PersonalSpace", "SocialCost", "agf", "agf_algorithm1"]
