"""Who is where at time t: the people model every consumer reads.

The cost, the checkers, the plant, the figures, the replay and the metrics
ask a :class:`PeopleModel` for a :class:`PeopleState` at a time ``t``
instead of reading the scenario's people. :class:`StaticPeople` is the
first model (people who stand still); walking people are further models
behind the same protocol.
"""

from drake_social.people.log import PEOPLE_CSV_FIELDS, PeopleLog, person_ids
from drake_social.people.compose import CrowdModel, ScenarioPeople, people_model, with_people, without_people
from drake_social.people.model import PeopleModel, PeopleState, StaticPeople
from drake_social.people.prediction import Prediction, constant_velocity, perfect_prediction, predict

__all__ = ["PEOPLE_CSV_FIELDS", "CrowdModel", "PeopleLog", "PeopleModel", "PeopleState", "Prediction", "ScenarioPeople", "StaticPeople", "constant_velocity",
           "people_model", "perfect_prediction", "person_ids", "predict", "with_people", "without_people"]
