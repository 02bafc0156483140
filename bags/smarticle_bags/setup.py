"""ament_python package smarticle_bags: record, replay and analyse rosbag2-compatible mcap bags."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_bags'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description='Record, replay and analyse rosbag2-compatible mcap bags of smarticle runs.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'smarticle-bag = smarticle_bags.cli:main',
            'recorder = smarticle_bags.recorder_node:main',
            'player = smarticle_bags.player_node:main',
        ],
    },
)
