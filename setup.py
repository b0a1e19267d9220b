"""Build script of the hydro_sdp ament_python package."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'hydro_sdp'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*', 'bench']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config',
         sorted(glob('config/*.yaml')) + sorted(glob('config/*.xml'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hydro_sdp maintainers',
    maintainer_email='maintainers@hydro-sdp.invalid',
    description='SDP identification and PIP-IDZ control of hydraulic manipulator joints',
    license='Apache-2.0',
    extras_require={'test': ['pytest', 'hypothesis']},
    entry_points={
        'console_scripts': [
            'hydro-sdp = hydro_sdp.cli.main:entry_point',
            'plant_node = hydro_sdp.ros.entry_points:plant_node',
            'controller_node = hydro_sdp.ros.entry_points:controller_node',
            'identifier_node = hydro_sdp.ros.entry_points:identifier_node',
            'bag_recorder = hydro_sdp.ros.entry_points:bag_recorder',
            'bag_player = hydro_sdp.ros.entry_points:bag_player',
        ],
    },
)
