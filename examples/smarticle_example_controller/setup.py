"""ament_python package smarticle_example_controller: a user's own controller, as the guide builds it."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_example_controller'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description='An example of a user\'s own smarticle controller: a square gait that stops on contact.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'square_stop = smarticle_example_controller.square_stop:main',
        ],
    },
)
