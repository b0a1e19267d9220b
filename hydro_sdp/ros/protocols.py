"""What the nodes' parts need of rclpy objects, as Protocols (tests may hand in stand-ins)."""

from typing import Protocol


class MessagePublisher(Protocol):
    """A publisher: an rclpy ``Publisher``, or a stand-in that records what it is given."""

    def publish(self, msg: object) -> None:
        """Publish ``msg``."""

    def get_subscription_count(self) -> int:
        """Return how many subscriptions are matched."""
